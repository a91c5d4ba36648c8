// Fuzz target: the tile set index reader (the tools' tiles.json). Every text is refused with an
// std::invalid_argument (nothing else is thrown) or parsed; a parsed index keeps the reader's promises
// (levels 2 to 15, finite numbers, integer keys, tile files inside the set) and reads back the same from the
// JSON it writes.
#include <cmath>
#include <cstdint>
#include <cstdio>
#include <cstdlib>
#include <stdexcept>
#include <string>

#include "tile_index.h"

using fot_tools::TileIndex;

namespace {

void require(bool ok) {
  if (!ok) std::abort();
}

std::string quoted(const std::string& s) {
  std::string q = "\"";
  for (const char c : s) {
    if (c == '"' || c == '\\') q.push_back('\\');
    q.push_back(c);
  }
  return q + "\"";
}

std::string number(double v) {
  char text[32];
  std::snprintf(text, sizeof text, "%.17g", v);
  return text;
}

std::string numbers(const double* v, int n) {
  std::string s = "[";
  for (int i = 0; i < n; ++i) s += (i ? ", " : "") + number(v[i]);
  return s + "]";
}

/** The index as tiles.py writes it, fields in another order. */
std::string write(const TileIndex& index) {
  std::string s = "{\"tiles\": [";
  for (std::size_t i = 0; i < index.tiles.size(); ++i) {
    const TileIndex::Tile& t = index.tiles[i];
    const double at[3] = {double(t.index[0]), double(t.index[1]), double(t.index[2])};
    s += std::string(i ? ", " : "") + "{\"name\": " + quoted(t.name) + ", \"level\": " + number(t.level) +
         ", \"index\": " + numbers(at, 3) + ", \"file\": " + quoted(t.file) + "}";
  }
  return s + "], \"format\": \"pcl_fot tile set\", \"resolution\": " + number(index.resolution) +
         ", \"origin\": " + numbers(index.origin, 3) +
         ", \"sensor_model\": " + numbers(index.sensor_model, 5) +
         ", \"rule\": " + (index.log_odds ? "\"log_odds\"" : "\"binary\"") + "}";
}

bool same(const TileIndex& a, const TileIndex& b) {
  bool equal = a.resolution == b.resolution && a.log_odds == b.log_odds && a.tiles.size() == b.tiles.size();
  for (int i = 0; i < 3; ++i) equal &= a.origin[i] == b.origin[i];
  for (int i = 0; i < 5; ++i) equal &= a.sensor_model[i] == b.sensor_model[i];
  for (std::size_t i = 0; equal && i < a.tiles.size(); ++i) {
    const TileIndex::Tile &s = a.tiles[i], &t = b.tiles[i];
    equal &= s.name == t.name && s.file == t.file && s.level == t.level && s.index[0] == t.index[0] &&
             s.index[1] == t.index[1] && s.index[2] == t.index[2];
  }
  return equal;
}

}  // namespace

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
  const std::string text(reinterpret_cast<const char*>(data), size);
  TileIndex index;
  try {
    index = fot_tools::parseTileIndex(text);
  } catch (const std::invalid_argument& e) {
    require(e.what()[0] != '\0');
    return 0;
  }
  require(std::isfinite(index.resolution));
  for (const double v : index.origin) require(std::isfinite(v));
  for (const double v : index.sensor_model) require(std::isfinite(v));
  for (const TileIndex::Tile& t : index.tiles) {
    require(t.level >= 2 && t.level <= 15);
    require(!t.file.empty() && t.file[0] != '/' && t.file.find("..") == std::string::npos);
    for (const std::int64_t k : t.index) require(std::llabs(k) <= 1000000000);
  }
  require(same(fot_tools::parseTileIndex(write(index)), index));
  return 0;
}
