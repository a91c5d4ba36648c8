#include <pcl_fot/scan_insertion.h>

#include <cmath>
#include <stdexcept>
#include <string>
#include <vector>

#include <pcl_fot/accessor.h>
#include <pcl_fot/ray_caster.h>

namespace pcl {
namespace fot {
namespace {

/**
 * The tree's side. With LineBurstAccess, a ray's cells come grouped by leaf, and a table remembers the
 * 4×4×4 blocks written lately: neighbouring rays cross the same leaves again and again, and the table
 * answers for them. A block's first leaf is written at once, so that a cube the tree reports free already
 * is passed without touching it: the last visited node answers for the next cells. The block's later cells
 * wait in the table and go into the tree a block at a time, when another block takes the slot, the block
 * is all free, or the rays are done: one short access per leaf instead of one from wherever the ray was.
 * Phase 1 only ever adds free cells, so a cube found free stays free. Without LineBurstAccess, every cell is
 * its own access from the root.
 */
class TreeWriter {
 public:
  /** `rays`, the scan's size, sizes the table of written blocks: one entry per ray, 2^10 to 2^16. */
  TreeWriter(FastOctTree& t, bool line_burst, std::size_t rays)
      : accessor_(t, line_burst), line_burst_(line_burst) {
    if (!line_burst) return;
    while (written_bits_ < 16 && (std::size_t(1) << written_bits_) < rays) ++written_bits_;
    written_.resize(std::size_t(1) << written_bits_);
  }

  std::size_t freeRay(const VoxelGrid& grid, const float from[3], const float to[3]) {
    if (!line_burst_)
      return traceSegment(grid, from, to, [&](const Key& k) { accessor_.setValidCell(k, CellState::Free); });
    return traceSegmentLeaves(grid, from, to, [&](const Key& k, std::uint32_t mask) { freeLeaf(k, mask); });
  }

  /** Writes the cells still waiting in the table; the rays' free cells are all in the tree afterwards. */
  void finishFree() {
    for (Written& w : written_) flush(w);
  }

  void occupied(const Key& k) { accessor_.setValidCell(k, CellState::Occupied); }

 private:
  /** Cells this writer made free in one 4×4×4 block: they stay free until the scan's endpoints. */
  struct Written {
    std::uint32_t block[3] = {0, 0, 0};  // tree coordinates / 4
    std::uint64_t cells = 0;             // bit 8 * leaf + octant
    std::uint64_t pending = 0;           // the subset not written to the tree yet
  };

  void freeLeaf(const Key& k, std::uint32_t mask) {
    const std::uint32_t u[3] = {tree_coord::fromKey(k.x), tree_coord::fromKey(k.y), tree_coord::fromKey(k.z)};
    if (skip_ != 0 && ((u[0] ^ cube_[0]) | (u[1] ^ cube_[1]) | (u[2] ^ cube_[2])) >> skip_ == 0) return;
    const std::uint32_t block[3] = {u[0] >> 2, u[1] >> 2, u[2] >> 2};
    Written& w = written_[(block[0] * 0x9E3779B1u ^ block[1] * 0x85EBCA77u ^ block[2] * 0xC2B2AE3Du) >>
                          (32 - written_bits_)];
    const std::uint64_t cells = std::uint64_t(mask) << (8 * tree_coord::octant(u[0], u[1], u[2], 2));
    if (w.block[0] == block[0] && w.block[1] == block[1] && w.block[2] == block[2]) {
      w.pending |= cells & ~w.cells;
      w.cells |= cells;
      if (w.cells == ~std::uint64_t(0)) flush(w);  // a whole free block: let the tree fold it now
      return;
    }
    flush(w);
    w.block[0] = block[0], w.block[1] = block[1], w.block[2] = block[2];
    w.cells = cells;
    const unsigned skip = accessor_.setValidLeafCells(k, mask, CellState::Free);
    if (skip == 0) return;
    skip_ = skip;
    cube_[0] = u[0], cube_[1] = u[1], cube_[2] = u[2];
  }

  void flush(Written& w) {
    if (w.pending == 0) return;
    for (unsigned leaf = 0; leaf < 8; ++leaf) {
      const std::uint32_t mask = std::uint32_t(w.pending >> (8 * leaf)) & 0xFFu;
      if (mask == 0) continue;
      const Key k{tree_coord::toKey(4 * w.block[0] + 2 * (leaf & 1u)),
                  tree_coord::toKey(4 * w.block[1] + (leaf & 2u)),
                  tree_coord::toKey(4 * w.block[2] + (leaf & 4u) / 2)};
      accessor_.setValidLeafCells(k, mask, CellState::Free);
    }
    w.pending = 0;
  }

  Accessor accessor_;
  bool line_burst_;
  unsigned skip_ = 0;  // a cube known free: the 2^skip_ cells around cube_ per axis (0: none)
  std::uint32_t cube_[3] = {0, 0, 0};
  unsigned written_bits_ = 10;
  std::vector<Written> written_;
};

class GridWriter {
 public:
  explicit GridWriter(FastOccMesh& g) : grid_(g) {}
  std::size_t freeRay(const VoxelGrid& grid, const float from[3], const float to[3]) {
    return traceSegment(grid, from, to, [&](const Key& k) {
      if (grid_.contains(k)) grid_.setCell(k, CellState::Free);
    });
  }
  void finishFree() {}
  void occupied(const Key& k) {
    if (grid_.contains(k)) grid_.setCell(k, CellState::Occupied);
  }

 private:
  FastOccMesh& grid_;
};

/** A ray may step one cell past its end keys; keep those cells inside the key range too. */
bool traceable(const Key& k) {
  return k.x > kMinKey && k.x < kMaxKey && k.y > kMinKey && k.y < kMaxKey && k.z > kMinKey && k.z < kMaxKey;
}

template <typename Writer>
ScanStats insert(Writer& writer, const VoxelGrid& grid, const float sensor[3], const float* xyz,
                 std::size_t count, std::size_t stride_bytes, const ScanOptions& options) {
  if (!std::isfinite(sensor[0]) || !std::isfinite(sensor[1]) || !std::isfinite(sensor[2]))
    throw std::invalid_argument("pcl::fot::insertRays: the sensor position is not finite");
  Key sensor_key;
  if (!grid.pointToKey(sensor[0], sensor[1], sensor[2], sensor_key) || !traceable(sensor_key))
    throw std::out_of_range("pcl::fot::insertRays: the sensor lies beyond the key range");

  ScanStats stats;
  std::vector<Key> endpoints;
  endpoints.reserve(count);
  const char* bytes = reinterpret_cast<const char*>(xyz);
  for (std::size_t i = 0; i < count; ++i) {
    const float* p = reinterpret_cast<const float*>(bytes + i * stride_bytes);
    if (!std::isfinite(p[0]) || !std::isfinite(p[1]) || !std::isfinite(p[2])) {
      ++stats.non_finite;
      continue;
    }
    // OctoMap's arithmetic: a float difference, its squared norm summed in float.
    const float d[3] = {p[0] - sensor[0], p[1] - sensor[1], p[2] - sensor[2]};
    const double dist = std::sqrt(double(d[0] * d[0] + d[1] * d[1] + d[2] * d[2]));
    if (dist < options.min_range) {
      ++stats.too_close;
      continue;
    }
    if (options.max_range > 0.0 && dist > options.max_range) {
      const float len = float(dist), range = float(options.max_range);
      const float end[3] = {sensor[0] + d[0] / len * range, sensor[1] + d[1] / len * range,
                            sensor[2] + d[2] / len * range};
      Key end_key;
      if (!grid.pointToKey(end[0], end[1], end[2], end_key) || !traceable(end_key)) {
        ++stats.out_of_range;
        continue;
      }
      stats.ray_cells += writer.freeRay(grid, sensor, end);
      ++stats.truncated;
      ++stats.rays;
      continue;
    }
    Key key;
    if (!grid.pointToKey(p[0], p[1], p[2], key) || !traceable(key)) {
      ++stats.out_of_range;
      continue;
    }
    stats.ray_cells += writer.freeRay(grid, sensor, p);
    endpoints.push_back(key);
    ++stats.rays;
  }
  // Endpoints last: within a scan, occupied wins over free.
  writer.finishFree();
  for (const Key& k : endpoints) writer.occupied(k);
  stats.occupied = endpoints.size();
  return stats;
}

}  // namespace

ScanStats insertRays(FastOctTree& map, const float sensor[3], const float* xyz, std::size_t count,
                     std::size_t stride_bytes, const ScanOptions& options) {
  TreeWriter writer(map, options.line_burst, count);
  return insert(writer, map.getGrid(), sensor, xyz, count, stride_bytes, options);
}

ScanStats insertRays(FastOccMesh& map, const float sensor[3], const float* xyz, std::size_t count,
                     std::size_t stride_bytes, const ScanOptions& options) {
  GridWriter writer(map);
  return insert(writer, map.getGrid(), sensor, xyz, count, stride_bytes, options);
}

}  // namespace fot
}  // namespace pcl
