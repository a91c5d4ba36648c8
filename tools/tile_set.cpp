#include "tile_set.h"

#include <dirent.h>
#include <sys/stat.h>

#include <stdexcept>
#include <vector>

#include <pcl_fot/io/file_io.h>
#include <pcl_fot/io/fot_file.h>

#include "arguments.h"
#include "tile_index.h"

namespace fot_tools {
namespace {

constexpr const char* kIndexName = "tiles.json";
constexpr std::size_t kMaxIndexBytes = std::size_t(256) << 20;

bool isDirectory(const std::string& path) {
  struct stat st;
  return stat(path.c_str(), &st) == 0 && S_ISDIR(st.st_mode);
}

std::string indexOf(const std::string& path) {
  return isDirectory(path) ? path + "/" + kIndexName : path;
}

/** Appends the entries of a folder, and those of its folders, to `files`. */
void listFiles(const std::string& folder, bool descend, std::vector<std::string>& files) {
  DIR* dir = opendir(folder.c_str());
  if (!dir) return;
  while (const dirent* entry = readdir(dir)) {
    if (entry->d_name[0] == '.') continue;
    const std::string path = folder + "/" + entry->d_name;
    files.push_back(path);
    if (descend && isDirectory(path)) listFiles(path, false, files);
  }
  closedir(dir);
}

}  // namespace

bool isTileSet(const std::string& path) {
  const std::string index = indexOf(path);
  return index.size() >= 10 && index.compare(index.size() - 10, 10, kIndexName) == 0;
}

std::vector<std::string> tileSetFiles(const std::string& path) {
  const std::string index = indexOf(path);
  const std::string tiles = index.substr(0, index.find_last_of('/') + 1) + "tiles";
  std::vector<std::string> files{index};
  listFiles(tiles, true, files);  // a run's tiles lie in tiles/<run>/
  return files;
}

pcl::fot::FastOctTree loadTileSet(const std::string& path, std::size_t max_bytes) {
  const std::string index_path = indexOf(path);
  const std::string base = index_path.substr(0, index_path.find_last_of('/') + 1);
  pcl::fot::FastOctTree whole(1.0);
  TileIndex index;
  try {
    index = parseTileIndex(pcl::fot::io::readFile(index_path, kMaxIndexBytes));
    const double* o = index.origin;
    const double* m = index.sensor_model;
    whole = pcl::fot::FastOctTree(index.resolution, o[0], o[1], o[2]);
    whole.setSensorModel(pcl::fot::SensorModel(m[0], m[1], m[2], m[3], m[4]));
    whole.setUpdateRule(index.log_odds ? pcl::fot::UpdateRule::LogOdds : pcl::fot::UpdateRule::Binary);
    whole.setMaxMemoryBytes(max_bytes);
  } catch (const std::exception& e) {
    throw ToolError(kExitInput, index_path + ": " + e.what());
  }
  for (const TileIndex::Tile& tile : index.tiles) {
    try {
      const pcl::fot::FastOctTree part = pcl::fot::io::loadFot(base + tile.file, max_bytes);
      if (!(part.getGrid() == whole.getGrid())) throw std::invalid_argument("its grid is not the tile set's");
      const std::int64_t edge = std::int64_t(1) << tile.level;
      std::int64_t lo[3];
      for (int a = 0; a < 3; ++a) lo[a] = tile.index[a] * edge;
      part.forEachRegion([&](const pcl::fot::Region& r) {
        const std::int64_t k[3] = {r.min_key.x, r.min_key.y, r.min_key.z}, size = std::int64_t(1) << r.level;
        for (int a = 0; a < 3; ++a)
          if (k[a] < lo[a] || k[a] + size > lo[a] + edge)
            throw std::invalid_argument("it holds cells outside its cube");
        return true;
      });
      whole.merge(part);
    } catch (const ToolError&) {
      throw;
    } catch (const pcl::fot::MemoryLimitError&) {
      throw;
    } catch (const std::exception& e) {
      throw ToolError(kExitInput, "tile " + tile.name + " of " + index_path + ": " + e.what());
    }
  }
  return whole;
}

}  // namespace fot_tools
