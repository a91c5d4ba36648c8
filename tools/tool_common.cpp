#include "tool_common.h"

#include "tile_set.h"

#include <algorithm>
#include <cctype>
#include <cmath>
#include <cstdlib>

#include <sys/stat.h>
#include <unistd.h>

#include <pcl/console/print.h>

#include <pcl_fot/io/fot_file.h>
#include <pcl_fot/io/octomap.h>

namespace fot_tools {
void refuseOverwrites(const std::vector<std::string>& inputs, const std::vector<std::string>& outputs) {
  struct Identity {
    dev_t device;
    ino_t inode;
    bool operator==(const Identity& o) const { return device == o.device && inode == o.inode; }
  };
  auto identity = [](const std::string& path, Identity& id) {
    struct stat st;
    if (::stat(path.c_str(), &st) != 0) return false;  // follows links; a file yet to be made is no input
    id = Identity{st.st_dev, st.st_ino};
    return true;
  };
  for (std::size_t o = 0; o < outputs.size(); ++o) {
    Identity out;
    if (!identity(outputs[o], out)) continue;
    for (const std::string& input : inputs) {
      Identity in;
      if (identity(input, in) && in == out)
        throw ToolError(kExitUsage, "the output '" + outputs[o] + "' is the input '" + input +
                                        "' (the same file): it would be overwritten");
    }
    for (std::size_t other = 0; other < o; ++other) {
      Identity id;
      if (identity(outputs[other], id) && id == out)
        throw ToolError(kExitUsage,
                        "the outputs '" + outputs[other] + "' and '" + outputs[o] + "' are the same file");
    }
  }
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
  if (isTileSet(path)) return true;
  const std::string ext = extension(path);
  return ext == ".fot" || ext == ".bt" || ext == ".ot";
}

std::size_t maxMemory(const Arguments& args) {
  double mib = 1024;
  args.getPositive("-max_memory", mib);
  if (!(mib < 1e12)) throw ToolError(kExitUsage, "option -max_memory takes MiB, below 1e12");
  return std::size_t(std::max(1.0, mib * 1048576.0));
}

pcl::fot::FastOctTree loadMap(const std::string& path, std::size_t max_bytes) {
  if (isTileSet(path)) return loadTileSet(path, max_bytes);
  const std::string ext = extension(path);
  pcl::fot::io::OctoMapImportOptions options;
  options.max_pool_bytes = max_bytes;
  if (ext == ".fot") return pcl::fot::io::loadFot(path, max_bytes);
  if (ext == ".bt") return pcl::fot::io::loadBt(path, options);
  if (ext == ".ot") return pcl::fot::io::loadOt(path, options);
  throw ToolError(kExitUsage, "'" + path + "' is not a .fot, .bt or .ot map or a tile set");
}

}  // namespace fot_tools
