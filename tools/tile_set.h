#pragma once
// Tile sets of the Python package's tiled mapping (python/pcl_fot/tiles.py), read as one map by the tools.

#include <cstddef>
#include <string>
#include <vector>

#include <pcl_fot/tree/fast_oct_tree.h>

namespace fot_tools {

/** A directory holding tiles.json, or a path to such an index file. */
bool isTileSet(const std::string& path);

/** The tile set's index and the files in its tiles/ folder and its runs' folders there: what an output must
 * not overwrite. */
std::vector<std::string> tileSetFiles(const std::string& path);

/**
 * The map a tile set holds: its tiles (.fot files the index names) merged, in the index's grid, rule and
 * sensor model. Throws ToolError naming the index or the tile for a missing, damaged or misplaced tile, a
 * tile of another grid, or a map beyond max_bytes.
 */
pcl::fot::FastOctTree loadTileSet(const std::string& path, std::size_t max_bytes);

}  // namespace fot_tools
