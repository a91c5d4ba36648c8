#include <pcl_fot/scan_insertion.h>

#include <cmath>
#include <stdexcept>
#include <string>
#include <vector>

#include <pcl_fot/accessor.h>

#include "block_ray_walker.h"

namespace pcl {
namespace fot {
namespace {

/** Calls `visit(const Key&)` for each cell of the walker's stretch `i`. */
template <typename Visit>
void forEachCell(const detail::BlockRayWalker& walker, std::size_t i, Visit&& visit) {
  const std::uint32_t block[3] = {walker.blockX(i), walker.blockY(i), walker.blockZ(i)};
  for (std::uint64_t cells = walker.cells(i); cells != 0; cells &= cells - 1) {
    const unsigned bit = unsigned(__builtin_ctzll(cells));
    visit(Key{tree_coord::toKey(4 * block[0] + (bit & 3u)), tree_coord::toKey(4 * block[1] + (bit >> 2 & 3u)),
              tree_coord::toKey(4 * block[2] + (bit >> 4))});
  }
}

/**
 * The tree's side. With LineBurstAccess, the rays' cells come a 4×4×4 block at a time, and a table
 * remembers the blocks written lately: neighbouring rays cross the same blocks again and again, and the
 * table answers for them. A block's first leaf is written at once, so that a cube the tree reports free
 * already is passed without touching it: the last visited node answers for the next cells. The block's
 * other cells wait in the table and go into the tree a block at a time, when another block takes the slot,
 * the block is all free, or the rays are done: one short access per leaf instead of one from wherever the
 * last ray was. Phase 1 only ever adds free cells, so a cube found free stays free. Without
 * LineBurstAccess, every cell is its own access from the root.
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

  /** The walker's batch of `n` stretches. */
  void freeStretches(const detail::BlockRayWalker& walker, std::size_t n) {
    if (!line_burst_) {
      for (std::size_t i = 0; i < n; ++i)
        forEachCell(walker, i, [&](const Key& k) { accessor_.setValidCell(k, CellState::Free); });
      return;
    }
    for (std::size_t i = 0; i < n; ++i) {
      const std::uint32_t block[3] = {walker.blockX(i), walker.blockY(i), walker.blockZ(i)};
      const std::uint64_t cells = walker.cells(i);
      if (skip_ != 0 &&
          (((block[0] << 2) ^ cube_[0]) | ((block[1] << 2) ^ cube_[1]) | ((block[2] << 2) ^ cube_[2])) >>
                  skip_ ==
              0)
        continue;
      Written& w = entry(block);
      if (w.block[0] != block[0] || w.block[1] != block[1] || w.block[2] != block[2]) {
        replace(w, block, cells);
        continue;
      }
      const std::uint64_t fresh = cells & ~w.cells;
      w.pending |= fresh;
      w.cells |= cells;
      // A block that just filled goes to the tree now, which folds it. Rays keep crossing full blocks, so
      // one branch tests both conditions: it is rarely taken and easy to predict.
      if ((~w.cells | std::uint64_t(fresh == 0)) == 0) flush(w);
    }
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
    std::uint64_t cells = 0;             // see detail::block_cells
    std::uint64_t pending = 0;           // the subset not written to the tree yet
  };

  /** Takes a new block into its slot, whose block goes to the tree; off the hot path of blocks seen. */
  __attribute__((noinline)) void replace(Written& w, const std::uint32_t (&block)[3], std::uint64_t cells) {
    flush(w);
    w.block[0] = block[0], w.block[1] = block[1], w.block[2] = block[2];
    w.cells = cells;
    const unsigned leaf = detail::block_cells::leafOf(unsigned(__builtin_ctzll(cells)));
    w.pending = cells & ~detail::block_cells::leafBits(leaf);
    const unsigned skip = accessor_.setValidLeafCells(
        leafKey(w.block, leaf), detail::block_cells::leafMask(cells, leaf), CellState::Free);
    if (skip < 2) return;  // the cube must hold whole blocks
    skip_ = skip;
    cube_[0] = block[0] << 2, cube_[1] = block[1] << 2, cube_[2] = block[2] << 2;
  }

  Written& entry(const std::uint32_t (&block)[3]) {
    return written_[(block[0] * 0x9E3779B1u ^ block[1] * 0x85EBCA77u ^ block[2] * 0xC2B2AE3Du) >>
                    (32 - written_bits_)];
  }

  static Key leafKey(const std::uint32_t (&block)[3], unsigned leaf) {
    return Key{tree_coord::toKey(4 * block[0] + 2 * (leaf & 1u)),
               tree_coord::toKey(4 * block[1] + (leaf & 2u)),
               tree_coord::toKey(4 * block[2] + (leaf & 4u) / 2)};
  }

  void flush(Written& w) {
    for (std::uint64_t p = w.pending; p != 0;) {
      const unsigned leaf = detail::block_cells::leafOf(unsigned(__builtin_ctzll(p)));
      accessor_.setValidLeafCells(leafKey(w.block, leaf), detail::block_cells::leafMask(p, leaf),
                                  CellState::Free);
      p &= ~detail::block_cells::leafBits(leaf);
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
  void freeStretches(const detail::BlockRayWalker& walker, std::size_t n) {
    for (std::size_t i = 0; i < n; ++i)
      forEachCell(walker, i, [&](const Key& k) {
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
  std::vector<float> ends;  // xyz of each ray's end
  ends.reserve(3 * count);
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
      ends.insert(ends.end(), end, end + 3);
      ++stats.truncated;
      ++stats.rays;
      continue;
    }
    Key key;
    if (!grid.pointToKey(p[0], p[1], p[2], key) || !traceable(key)) {
      ++stats.out_of_range;
      continue;
    }
    ends.insert(ends.end(), p, p + 3);
    endpoints.push_back(key);
    ++stats.rays;
  }
  detail::BlockRayWalker walker(grid, sensor, ends.data(), ends.size() / 3);
  while (const std::size_t n = walker.next()) writer.freeStretches(walker, n);
  writer.finishFree();
  stats.ray_cells = walker.cellCount();
  // Endpoints last: within a scan, occupied wins over free.
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
