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
 * The tree's side. With LineBurstAccess, a ray's cells come in runs through the same 2×2×2 leaf, so they
 * are marked free a leaf at a time, and cubes the tree reports free already are passed without touching
 * it: the last visited node answers for the next cells. Phase 1 only ever adds free cells, so a cube found
 * free stays free, even for the following rays; so do the cells of the leaves written lately, which a
 * small table remembers: neighbouring rays cross the same leaves again and again. Without LineBurstAccess,
 * every cell is its own access from the root.
 */
class TreeWriter {
 public:
  /** `rays`, the scan's size, sizes the table of written leaves: one entry per ray, 2^10 to 2^16. */
  TreeWriter(FastOctTree& t, bool line_burst, std::size_t rays)
      : accessor_(t, line_burst), line_burst_(line_burst) {
    if (!line_burst) return;
    while (written_bits_ < 16 && (std::size_t(1) << written_bits_) < rays) ++written_bits_;
    written_.resize(std::size_t(1) << written_bits_);
  }

  void freeRun(const Key* cells, int n) {
    if (!line_burst_) {
      for (int i = 0; i < n; ++i) accessor_.setValidCell(cells[i], CellState::Free);
      return;
    }
    Pending p = pending_;  // a local copy stays in registers across the loop
    for (int i = 0; i < n; ++i) {
      const std::uint32_t u[3] = {tree_coord::fromKey(cells[i].x), tree_coord::fromKey(cells[i].y),
                                  tree_coord::fromKey(cells[i].z)};
      if (p.skip > 0 && (((u[0] ^ p.cube[0]) | (u[1] ^ p.cube[1]) | (u[2] ^ p.cube[2])) >> p.skip) == 0)
        continue;
      const std::uint32_t bit = 1u << tree_coord::octant(u[0], u[1], u[2], 1);
      if (p.mask != 0 && (((u[0] ^ p.leaf[0]) | (u[1] ^ p.leaf[1]) | (u[2] ^ p.leaf[2])) >> 1) == 0) {
        p.mask |= bit;
        continue;
      }
      write(p);
      p.key = cells[i];
      p.leaf[0] = u[0], p.leaf[1] = u[1], p.leaf[2] = u[2];
      p.mask = bit;
    }
    pending_ = p;
  }

  void endRay() { write(pending_); }

  void occupied(const Key& k) { accessor_.setValidCell(k, CellState::Occupied); }

 private:
  struct Pending {
    Key key;
    std::uint32_t mask = 0, leaf[3] = {0, 0, 0};  // the pending cells of one leaf
    unsigned skip = 0;                            // a cube known free: 2^skip cells around cube
    std::uint32_t cube[3] = {0, 0, 0};
  };

  /** A leaf this writer made cells free in, and which: they stay free until the scan's endpoints. */
  struct Written {
    std::uint32_t leaf[3] = {0, 0, 0};  // tree coordinates halved
    std::uint32_t mask = 0;
  };

  void write(Pending& p) {
    if (p.mask == 0) return;
    const std::uint32_t leaf[3] = {p.leaf[0] >> 1, p.leaf[1] >> 1, p.leaf[2] >> 1};
    Written& w = written_[(leaf[0] * 0x9E3779B1u ^ leaf[1] * 0x85EBCA77u ^ leaf[2] * 0xC2B2AE3Du) >>
                          (32 - written_bits_)];
    const bool same = w.leaf[0] == leaf[0] && w.leaf[1] == leaf[1] && w.leaf[2] == leaf[2];
    if (same && (p.mask & ~w.mask) == 0) {  // neighbouring rays cross the same leaves again and again
      p.mask = 0;
      return;
    }
    p.skip = accessor_.setValidLeafCells(p.key, p.mask, CellState::Free);
    p.cube[0] = p.leaf[0], p.cube[1] = p.leaf[1], p.cube[2] = p.leaf[2];
    w.mask = (same ? w.mask : 0u) | p.mask;
    w.leaf[0] = leaf[0], w.leaf[1] = leaf[1], w.leaf[2] = leaf[2];
    p.mask = 0;
  }

  Accessor accessor_;
  bool line_burst_;
  Pending pending_;
  unsigned written_bits_ = 10;
  std::vector<Written> written_;
};

class GridWriter {
 public:
  explicit GridWriter(FastOccMesh& g) : grid_(g) {}
  void freeRun(const Key* cells, int n) {
    for (int i = 0; i < n; ++i)
      if (grid_.contains(cells[i])) grid_.setCell(cells[i], CellState::Free);
  }
  void endRay() {}
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
  auto mark_free = [&](const Key* cells, int n) { writer.freeRun(cells, n); };
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
      stats.ray_cells += traceSegmentRuns(grid, sensor, end, mark_free);
      writer.endRay();
      ++stats.truncated;
      ++stats.rays;
      continue;
    }
    Key key;
    if (!grid.pointToKey(p[0], p[1], p[2], key) || !traceable(key)) {
      ++stats.out_of_range;
      continue;
    }
    stats.ray_cells += traceSegmentRuns(grid, sensor, p, mark_free);
    writer.endRay();
    endpoints.push_back(key);
    ++stats.rays;
  }
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
