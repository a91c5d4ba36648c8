#include "tool_common.h"

#include <algorithm>
#include <cctype>
#include <cmath>
#include <cstdlib>
#include <sstream>

#include <sys/stat.h>
#include <unistd.h>

#include <pcl/console/print.h>

#include <pcl_fot/io/fot_file.h>
#include <pcl_fot/io/octomap.h>

namespace fot_tools {
namespace {

bool looksLikeNumber(const std::string& s) {
  char* end = nullptr;
  std::strtod(s.c_str(), &end);
  return end != s.c_str() && *end == '\0';
}

}  // namespace

Arguments::Arguments(int argc, char** argv, std::set<std::string> valued, std::set<std::string> switches)
    : argc_(argc), argv_(argv) {
  for (int i = 1; i < argc; ++i) {
    const std::string a = argv[i];
    if (a.size() > 1 && a[0] == '-' && !looksLikeNumber(a)) {
      if (valued.count(a)) {
        if (i + 1 >= argc) throw ToolError(kExitUsage, "option " + a + " needs a value (see -h)");
        ++i;
      } else if (!switches.count(a)) {
        throw ToolError(kExitUsage, "unknown option " + a + " (see -h)");
      }
      continue;
    }
    positional_.push_back(a);
  }
}

bool Arguments::get(const std::string& name, double& value) const {
  if (pcl::console::find_argument(argc_, argv_, name.c_str()) < 0) return false;
  if (pcl::console::parse_argument(argc_, argv_, name.c_str(), value) < 0 || !std::isfinite(value))
    throw ToolError(kExitUsage, "option " + name + " needs a finite number");
  return true;
}

bool Arguments::get(const std::string& name, int& value) const {
  if (pcl::console::find_argument(argc_, argv_, name.c_str()) < 0) return false;
  if (pcl::console::parse_argument(argc_, argv_, name.c_str(), value) < 0)
    throw ToolError(kExitUsage, "option " + name + " needs a whole number");
  return true;
}

bool Arguments::get(const std::string& name, std::string& value) const {
  return pcl::console::parse_argument(argc_, argv_, name.c_str(), value) >= 0;
}

bool Arguments::get(const std::string& name, std::vector<double>& values, std::size_t count) const {
  std::string text;
  if (!get(name, text)) return false;
  values.clear();
  std::stringstream in(text);
  std::string item;
  while (std::getline(in, item, ',')) {
    char* end = nullptr;
    const double v = std::strtod(item.c_str(), &end);
    if (item.empty() || *end != '\0' || !std::isfinite(v))
      throw ToolError(kExitUsage,
                      "option " + name + " takes " + std::to_string(count) + " comma-separated numbers");
    values.push_back(v);
  }
  if (values.size() != count)
    throw ToolError(kExitUsage,
                    "option " + name + " takes " + std::to_string(count) + " comma-separated numbers");
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

std::string extension(const std::string& path) {
  const std::size_t dot = path.rfind('.');
  if (dot == std::string::npos || path.find('/', dot) != std::string::npos) return "";
  std::string e = path.substr(dot);
  std::transform(e.begin(), e.end(), e.begin(), [](unsigned char c) { return char(std::tolower(c)); });
  return e;
}

void requireWritableDirectory(const std::string& file) {
  const std::size_t slash = file.find_last_of('/');
  const std::string dir = slash == std::string::npos ? "." : slash == 0 ? "/" : file.substr(0, slash);
  struct stat st;
  if (::stat(dir.c_str(), &st) != 0 || !S_ISDIR(st.st_mode))
    throw ToolError(kExitInput, "cannot write '" + file + "': the directory '" + dir + "' does not exist");
  if (::access(dir.c_str(), W_OK | X_OK) != 0)
    throw ToolError(kExitInput, "cannot write '" + file + "': the directory '" + dir + "' is not writable");
}

void requireRegularFile(const std::string& path, const std::string& what) {
  struct stat st;
  if (::stat(path.c_str(), &st) != 0) throw ToolError(kExitInput, "cannot read " + what + " '" + path + "'");
  if (!S_ISREG(st.st_mode)) throw ToolError(kExitInput, what + " '" + path + "' is not a regular file");
}

bool readLine(std::istream& in, std::string& line, std::size_t max_chars) {
  line.clear();
  for (int c; (c = in.get()) != '\n';) {
    if (c == std::char_traits<char>::eof()) return !line.empty();
    if (line.size() == max_chars) return false;
    line.push_back(char(c));
  }
  return true;
}

bool isMapFile(const std::string& path) {
  const std::string ext = extension(path);
  return ext == ".fot" || ext == ".bt" || ext == ".ot";
}

pcl::fot::FastOctTree loadMap(const std::string& path) {
  const std::string ext = extension(path);
  if (ext == ".fot") return pcl::fot::io::loadFot(path);
  if (ext == ".bt") return pcl::fot::io::loadBt(path);
  if (ext == ".ot") return pcl::fot::io::loadOt(path);
  throw ToolError(kExitUsage, "'" + path + "' is not a .fot, .bt or .ot map");
}

}  // namespace fot_tools
