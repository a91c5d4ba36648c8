#include "arguments.h"

#include <cctype>
#include <cerrno>
#include <cmath>
#include <cstdlib>
#include <limits>

#include <pcl_fot/tree/cell_grid.h>

namespace fot_tools {
namespace {

bool looksLikeNumber(const std::string& s) {
  char* end = nullptr;
  std::strtod(s.c_str(), &end);
  return end != s.c_str() && *end == '\0';
}

/** The whole text as a finite double; false otherwise (empty, trailing characters, NaN, Inf, overflow). */
bool parseNumber(const std::string& text, double& value) {
  if (text.empty() || std::isspace(static_cast<unsigned char>(text[0]))) return false;
  char* end = nullptr;
  errno = 0;
  value = std::strtod(text.c_str(), &end);
  return *end == '\0' && std::isfinite(value) && errno != ERANGE;
}

bool withinFloat(double v) {
  return std::abs(v) <= double(std::numeric_limits<float>::max());
}

}  // namespace

std::string printable(const std::string& text) {
  std::string out;
  for (const char c : text) {
    const unsigned char u = static_cast<unsigned char>(c);
    if (c == '\n') {
      out += "\\n";
    } else if (u < 0x20 || u == 0x7F) {
      const char hex[] = "0123456789abcdef";
      out += "\\x";
      out += hex[u >> 4];
      out += hex[u & 15u];
    } else {
      out += c;
    }
  }
  return out;
}

Arguments::Arguments(int argc, char** argv, std::set<std::string> valued, std::set<std::string> switches,
                     std::size_t min_positional, std::size_t max_positional) {
  for (int i = 1; i < argc; ++i) {
    const std::string a = argv[i];
    if (a == "-h" || a == "--help") help_ = true;
  }
  if (help_) return;
  for (int i = 1; i < argc; ++i) {
    const std::string a = argv[i];
    if (a.size() > 1 && a[0] == '-' && !looksLikeNumber(a)) {
      std::string value;
      if (valued.count(a)) {
        if (i + 1 >= argc) throw ToolError(kExitUsage, "option " + a + " needs a value");
        value = argv[++i];
        if (value.empty()) throw ToolError(kExitUsage, "option " + a + " needs a value, and it is empty");
      } else if (!switches.count(a)) {
        throw ToolError(kExitUsage, "unknown option " + printable(a));
      }
      if (!values_.emplace(a, value).second) throw ToolError(kExitUsage, "option " + a + " is given twice");
      continue;
    }
    positional_.push_back(a);
  }
  const std::size_t n = positional_.size();
  if (n > max_positional)
    throw ToolError(kExitUsage, "unexpected argument '" + printable(positional_[max_positional]) + "'");
  if (n < min_positional)
    throw ToolError(kExitUsage, "expected " + std::to_string(min_positional) +
                                    (max_positional == min_positional ? "" : " or more") +
                                    " file arguments, got " + std::to_string(n));
}

bool Arguments::get(const std::string& name, double& value) const {
  const auto it = values_.find(name);
  if (it == values_.end()) return false;
  if (!parseNumber(it->second, value))
    throw ToolError(kExitUsage, "option " + name + " needs a finite number");
  return true;
}

bool Arguments::get(const std::string& name, float& value) const {
  double v;
  if (!get(name, v)) return false;
  if (!withinFloat(v))
    throw ToolError(kExitUsage, "option " + name + " lies beyond a float's range (3.4e38)");
  value = float(v);
  return true;
}

bool Arguments::get(const std::string& name, int& value) const {
  const auto it = values_.find(name);
  if (it == values_.end()) return false;
  const std::string& text = it->second;
  char* end = nullptr;
  errno = 0;
  const long long v = std::strtoll(text.c_str(), &end, 10);
  if (std::isspace(static_cast<unsigned char>(text[0])) || *end != '\0' || errno == ERANGE ||
      v < std::numeric_limits<int>::min() || v > std::numeric_limits<int>::max())
    throw ToolError(kExitUsage, "option " + name + " needs a whole number");
  value = int(v);
  return true;
}

bool Arguments::get(const std::string& name, std::string& value) const {
  const auto it = values_.find(name);
  if (it == values_.end()) return false;
  value = it->second;
  return true;
}

bool Arguments::get(const std::string& name, std::vector<double>& values, std::size_t count,
                    bool as_float) const {
  std::string text;
  if (!get(name, text)) return false;
  const std::string what = "option " + name + " takes " + std::to_string(count) + " comma-separated numbers";
  values.clear();
  for (std::size_t start = 0;;) {
    const std::size_t comma = text.find(',', start);
    double v;
    if (!parseNumber(text.substr(start, comma == std::string::npos ? comma : comma - start), v))
      throw ToolError(kExitUsage, what);
    if (as_float && !withinFloat(v)) throw ToolError(kExitUsage, what + " within a float's range (3.4e38)");
    values.push_back(v);
    if (comma == std::string::npos) break;
    start = comma + 1;
  }
  if (values.size() != count) throw ToolError(kExitUsage, what);
  return true;
}

bool Arguments::getPositive(const std::string& name, double& value) const {
  if (!get(name, value)) return false;
  if (!(value > 0)) throw ToolError(kExitUsage, "option " + name + " must be positive");
  return true;
}

bool Arguments::getResolution(double& value) const {
  if (!getPositive("-res", value)) return false;
  const std::string why = pcl::fot::CellGrid::whyInvalid(value, 0.0, 0.0, 0.0);
  if (!why.empty()) throw ToolError(kExitUsage, "option -res: " + why);
  return true;
}

}  // namespace fot_tools
