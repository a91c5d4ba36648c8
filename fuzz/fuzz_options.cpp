// Fuzz target: the tools' option parser. The input is a command line, its arguments separated by NUL bytes.
// Every command line is refused with a one-line usage error (ToolError, exit code 1) or parsed; a parsed one
// keeps the tool's bounds on file arguments, and every value read is finite, at the precision asked for.
#include <cmath>
#include <cstdint>
#include <cstdlib>
#include <limits>
#include <string>
#include <vector>

#include "arguments.h"

using fot_tools::Arguments;
using fot_tools::ToolError;

namespace {

void require(bool ok) {
  if (!ok) std::abort();
}

/** Reads an option every way a tool does; a refusal must be a usage error. */
template <typename Read>
void read(Read&& how) {
  try {
    how();
  } catch (const ToolError& e) {
    require(e.code == fot_tools::kExitUsage && std::string(e.what()).find('\n') == std::string::npos);
  }
}

}  // namespace

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
  std::vector<std::string> words{"tool"};
  std::string word;
  for (std::size_t i = 0; i < size && words.size() < 64; ++i) {
    if (data[i] == 0) {
      words.push_back(word);
      word.clear();
    } else {
      word.push_back(char(data[i]));
    }
  }
  words.push_back(word);
  std::vector<char*> argv;
  for (std::string& w : words) argv.push_back(&w[0]);
  try {
    const Arguments args(int(argv.size()), argv.data(), {"-res", "-cap", "-guess", "-leaf", "-out"},
                         {"-free", "-h", "--help"}, 1, 2);
    if (args.helpAsked()) return 0;
    require(args.positional().size() >= 1 && args.positional().size() <= 2);
    read([&] {
      double v;
      if (args.get("-res", v)) require(std::isfinite(v));
    });
    read([&] {
      double v;
      if (args.getResolution(v)) require(v > 0 && std::isfinite(v));
    });
    read([&] {
      int v;
      args.get("-cap", v);
    });
    read([&] {
      float v;
      if (args.get("-leaf", v)) require(std::isfinite(v));
    });
    read([&] {
      std::vector<double> v;
      if (args.get("-guess", v, 4, true)) {
        require(v.size() == 4);
        for (double x : v) require(std::abs(x) <= double(std::numeric_limits<float>::max()));
      }
    });
    read([&] {
      std::string v;
      if (args.get("-out", v)) require(!v.empty());
    });
  } catch (const ToolError& e) {
    require(e.code == fot_tools::kExitUsage && std::string(e.what()).find('\n') == std::string::npos);
  }
  return 0;
}
