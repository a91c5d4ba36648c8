#include <pcl_fot/io/voxel_export.h>

#include <algorithm>
#include <cstdint>
#include <cstring>
#include <stdexcept>
#include <vector>

#include <pcl_fot/io/atomic_file.h>

namespace pcl {
namespace fot {
namespace io {

namespace {

struct Cell {
  float x, y, z;
  CellState state;
};

/** Blue through green to red: the "jet" ramp viewers use for height. */
std::uint32_t ramp(float t) {
  t = std::min(1.0f, std::max(0.0f, t));
  const float r = std::min(1.0f, std::max(0.0f, 1.5f - std::abs(4.0f * t - 3.0f)));
  const float g = std::min(1.0f, std::max(0.0f, 1.5f - std::abs(4.0f * t - 2.0f)));
  const float b = std::min(1.0f, std::max(0.0f, 1.5f - std::abs(4.0f * t - 1.0f)));
  return (std::uint32_t(r * 255) << 16) | (std::uint32_t(g * 255) << 8) | std::uint32_t(b * 255);
}

std::string pcdHeader(std::size_t n, bool rgb) {
  const std::string count = std::to_string(n);
  return std::string("# .PCD v0.7 - Point Cloud Data file format (pcl_fot voxel centres)\nVERSION 0.7\n") +
         (rgb ? "FIELDS x y z rgb\nSIZE 4 4 4 4\nTYPE F F F U\nCOUNT 1 1 1 1\n"
              : "FIELDS x y z\nSIZE 4 4 4\nTYPE F F F\nCOUNT 1 1 1\n") +
         "WIDTH " + count + "\nHEIGHT 1\nVIEWPOINT 0 0 0 1 0 0 0\nPOINTS " + count + "\nDATA binary\n";
}

}  // namespace

std::size_t saveVoxelCentersPCD(const FastOctTree& tree, const std::string& path,
                                const VoxelExportOptions& options) {
  const std::uint64_t total = tree.getOccupiedCount() + (options.include_free ? tree.getFreeCount() : 0);
  if (total > options.max_cells)
    throw std::length_error("pcl::fot::io::saveVoxelCentersPCD: " + std::to_string(total) +
                            " cells exceed the limit of " + std::to_string(options.max_cells));
  std::vector<Cell> cells;
  cells.reserve(std::size_t(total));
  const VoxelGrid& grid = tree.getGrid();
  auto collect = [&](CellState s) {
    tree.forEachCell(s, [&](const Key& k) {
      double x, y, z;
      grid.keyToCenter(k, x, y, z);
      cells.push_back({float(x), float(y), float(z), s});
    });
  };
  collect(CellState::Occupied);
  if (options.include_free) collect(CellState::Free);

  const bool rgb = options.coloring != VoxelColoring::None;
  float zmin = 0, zmax = 1;
  if (!cells.empty()) {
    const auto mm = std::minmax_element(cells.begin(), cells.end(),
                                        [](const Cell& a, const Cell& b) { return a.z < b.z; });
    zmin = mm.first->z;
    zmax = std::max(mm.second->z, zmin + 1e-6f);
  }
  std::string bytes = pcdHeader(cells.size(), rgb);
  const std::size_t stride = rgb ? 16 : 12;
  std::size_t at = bytes.size();
  bytes.resize(at + cells.size() * stride);
  for (const Cell& c : cells) {
    std::memcpy(&bytes[at], &c.x, 12);
    if (rgb) {
      const std::uint32_t color = options.coloring == VoxelColoring::Height
                                      ? ramp((c.z - zmin) / (zmax - zmin))
                                      : (c.state == CellState::Occupied ? 0xD03020u : 0x60C0F0u);
      std::memcpy(&bytes[at + 12], &color, 4);
    }
    at += stride;
  }
  writeFileAtomically(path, bytes);
  return cells.size();
}

}  // namespace io
}  // namespace fot
}  // namespace pcl
