#pragma once
// The index of a tile set (tiles.json, written by python/pcl_fot/tiles.py), read strictly.

#include <cstdint>
#include <string>
#include <vector>

namespace fot_tools {

/** What tiles.json says: the grid, rule and sensor model every tile shares, and the tiles. */
struct TileIndex {
  struct Tile {
    std::string name;
    std::string file;                   // relative to the index's folder, never leaving it
    int level = 0;                      // the tile is the tree's node at this level, 2 to 15
    std::int64_t index[3] = {0, 0, 0};  // its lowest key is index * 2^level
  };
  double resolution = 0;
  double origin[3] = {0, 0, 0};
  double sensor_model[5] = {0, 0, 0, 0, 0};  // hit, miss, clamp min, clamp max, occupancy
  bool log_odds = true;                      // else the binary rule
  std::vector<Tile> tiles;
};

/**
 * Parses an index. Throws std::invalid_argument saying what is wrong, and which tile ("tile <name>: ...")
 * for a flaw in one: text that is not JSON (or nested deeper than an index is), a missing field or one of
 * the wrong type, a number that is not finite or, where an integer is due, not an integer, a level outside 2
 * to 15, a tile file that is empty, absolute or reaches outside with "..". Values the map itself checks
 * (resolution, origin, sensor model) are left to it.
 */
TileIndex parseTileIndex(const std::string& text);

}  // namespace fot_tools
