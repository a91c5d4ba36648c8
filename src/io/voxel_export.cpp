#include <pcl_fot/io/voxel_export.h>

#include <algorithm>
#include <cstdint>
#include <cstring>
#include <stdexcept>
#include <vector>

#include <pcl_fot/io/file_io.h>
#include <pcl_fot/tree/accessor.h>

namespace pcl {
namespace fot {
namespace io {

namespace {

struct Cell {
  float x, y, z;
  CellState state;
  Key key;
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

/** The cells to export, refusing more than the options allow. */
std::vector<Cell> exportedCells(const FastOctTree& tree, const VoxelExportOptions& options, const char* who) {
  const std::uint64_t total = tree.getOccupiedCount() + (options.include_free ? tree.getFreeCount() : 0);
  if (total > options.max_cells)
    throw std::length_error(std::string("pcl::fot::io::") + who + ": " + std::to_string(total) +
                            " cells exceed the limit of " + std::to_string(options.max_cells));
  std::vector<Cell> cells;
  cells.reserve(std::size_t(total));
  const CellGrid& grid = tree.getGrid();
  auto collect = [&](CellState s) {
    tree.forEachCell(s, [&](const Key& k) {
      double x, y, z;
      grid.keyToCenter(k, x, y, z);
      cells.push_back({float(x), float(y), float(z), s, k});
    });
  };
  collect(CellState::Occupied);
  if (options.include_free) collect(CellState::Free);
  return cells;
}

/** Each cell's colour: by height over the exported cells, or by state. */
class Colors {
 public:
  Colors(const std::vector<Cell>& cells, VoxelColoring coloring) : coloring_(coloring) {
    if (cells.empty()) return;
    const auto mm = std::minmax_element(cells.begin(), cells.end(),
                                        [](const Cell& a, const Cell& b) { return a.z < b.z; });
    zmin_ = mm.first->z;
    zmax_ = std::max(mm.second->z, zmin_ + 1e-6f);
  }
  std::uint32_t operator()(const Cell& c) const {
    if (coloring_ == VoxelColoring::Height) return ramp((c.z - zmin_) / (zmax_ - zmin_));
    return c.state == CellState::Occupied ? 0xD03020u : 0x60C0F0u;
  }

 private:
  VoxelColoring coloring_;
  float zmin_ = 0, zmax_ = 1;
};

/** Appends v in big-endian order, as legacy VTK binary data is. */
template <typename T>
void putBigEndian(std::string& out, T v) {
  std::uint32_t bits;
  static_assert(sizeof(T) == 4, "32-bit values");
  std::memcpy(&bits, &v, 4);
  for (int i = 3; i >= 0; --i) out.push_back(char((bits >> (8 * i)) & 0xFFu));
}

}  // namespace

std::size_t saveVoxelCentersPCD(const FastOctTree& tree, const std::string& path,
                                const VoxelExportOptions& options) {
  const std::vector<Cell> cells = exportedCells(tree, options, "saveVoxelCentersPCD");
  const bool rgb = options.coloring != VoxelColoring::None;
  const Colors color(cells, options.coloring);
  std::string bytes = pcdHeader(cells.size(), rgb);
  const std::size_t stride = rgb ? 16 : 12;
  std::size_t at = bytes.size();
  bytes.resize(at + cells.size() * stride);
  for (const Cell& c : cells) {
    std::memcpy(&bytes[at], &c.x, 12);
    if (rgb) {
      const std::uint32_t rgb_value = color(c);
      std::memcpy(&bytes[at + 12], &rgb_value, 4);
    }
    at += stride;
  }
  writeFileAtomically(path, bytes);
  return cells.size();
}

std::size_t saveVoxelMeshVTK(const FastOctTree& tree, const std::string& path,
                             const VoxelExportOptions& options) {
  const std::vector<Cell> cells = exportedCells(tree, options, "saveVoxelMeshVTK");
  const Colors color(cells,
                     options.coloring == VoxelColoring::None ? VoxelColoring::Height : options.coloring);
  const CellGrid& grid = tree.getGrid();
  const double res = grid.resolution();
  // The 6 faces of a unit cube: the neighbour's offset and the corners, counter-clockwise seen from outside.
  struct Face {
    int dx, dy, dz;
    int corners[4][3];
  };
  static const Face faces[6] = {{-1, 0, 0, {{0, 0, 0}, {0, 0, 1}, {0, 1, 1}, {0, 1, 0}}},
                                {1, 0, 0, {{1, 0, 0}, {1, 1, 0}, {1, 1, 1}, {1, 0, 1}}},
                                {0, -1, 0, {{0, 0, 0}, {1, 0, 0}, {1, 0, 1}, {0, 0, 1}}},
                                {0, 1, 0, {{0, 1, 0}, {0, 1, 1}, {1, 1, 1}, {1, 1, 0}}},
                                {0, 0, -1, {{0, 0, 0}, {0, 1, 0}, {1, 1, 0}, {1, 0, 0}}},
                                {0, 0, 1, {{0, 0, 1}, {1, 0, 1}, {1, 1, 1}, {0, 1, 1}}}};
  ConstAccessor neighbours(tree);
  auto exported = [&](CellState s) {
    return s == CellState::Occupied || (options.include_free && s == CellState::Free);
  };
  std::string points, polygons, colors;
  std::size_t n = 0;
  for (const Cell& c : cells) {
    const std::uint32_t rgb = color(c);
    for (const Face& f : faces) {
      const Key k{c.key.x + f.dx, c.key.y + f.dy, c.key.z + f.dz};
      if (isValidKey(k) && exported(neighbours.getCell(k))) continue;
      for (const auto& corner : f.corners) {
        putBigEndian(points, float(grid.origin()[0] + (double(c.key.x) + corner[0]) * res));
        putBigEndian(points, float(grid.origin()[1] + (double(c.key.y) + corner[1]) * res));
        putBigEndian(points, float(grid.origin()[2] + (double(c.key.z) + corner[2]) * res));
        colors.push_back(char((rgb >> 16) & 0xFFu));
        colors.push_back(char((rgb >> 8) & 0xFFu));
        colors.push_back(char(rgb & 0xFFu));
      }
      putBigEndian(polygons, std::int32_t(4));
      for (int i = 0; i < 4; ++i) putBigEndian(polygons, std::int32_t(4 * n + i));
      ++n;
    }
  }
  const std::string faces_n = std::to_string(n), points_n = std::to_string(4 * n);
  std::string bytes = "# vtk DataFile Version 3.0\npcl_fot voxels\nBINARY\nDATASET POLYDATA\nPOINTS " +
                      points_n + " float\n" + points + "\nPOLYGONS " + faces_n + " " + std::to_string(5 * n) +
                      "\n" + polygons + "\nPOINT_DATA " + points_n + "\nCOLOR_SCALARS Colors 3\n" + colors +
                      "\n";
  writeFileAtomically(path, bytes);
  return n;
}

}  // namespace io
}  // namespace fot
}  // namespace pcl
