#include "bench_util.h"

#include <cstdarg>
#include <cstdint>
#include <cstdio>

namespace fot_bench {

void scrubCaches() {
  static std::vector<std::uint64_t> scratch(std::size_t(64) << 20 >> 3, 1);
  volatile std::uint64_t sink = 0;
  std::uint64_t sum = 0;
  for (std::size_t i = 0; i < scratch.size(); i += 8) sum += scratch[i];
  sink = sum;
  (void)sink;
}

std::string format(const char* fmt, ...) {
  va_list args, again;
  va_start(args, fmt);
  va_copy(again, args);
  const int n = std::vsnprintf(nullptr, 0, fmt, args);
  va_end(args);
  std::string out(std::size_t(n > 0 ? n : 0), '\0');
  std::vsnprintf(&out[0], out.size() + 1, fmt, again);
  va_end(again);
  return out;
}

std::string Table::markdown() const {
  std::string out = "|";
  for (const auto& h : header_) out += " " + h + " |";
  out += "\n|";
  for (std::size_t i = 0; i < header_.size(); ++i) out += i == 0 ? " --- |" : " ---: |";
  out += "\n";
  for (const auto& row : rows_) {
    out += "|";
    for (const auto& cell : row) out += " " + cell + " |";
    out += "\n";
  }
  return out;
}

}  // namespace fot_bench
