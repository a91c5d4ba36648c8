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
 * free stays free, even for the following rays. Without it, every cell is its own access from the root.
 */
class TreeWriter {
 public:
  TreeWriter(FastOctTree& t, bool line_burst) : accessor_(t, line_burst), line_burst_(line_burst) {}

  void freeRun(const Key* cells, int n) {
    if (!line_burst_) {
      for (int i = 0; i < n; ++i) accessor_.setValidCell(cells[i], CellState::Free);
      return;
    }
    for (int i = 0; i < n; ++i) {
      const std::uint32_t u[3] = {tree_coord::fromKey(cells[i].x), tree_coord::fromKey(cells[i].y),
                                  tree_coord::fromKey(cells[i].z)};
      if (skip_ > 0 && (((u[0] ^ cube_[0]) | (u[1] ^ cube_[1]) | (u[2] ^ cube_[2])) >> skip_) == 0) continue;
      const std::uint32_t bit = 1u << tree_coord::octant(u[0], u[1], u[2], 1);
      if (mask_ != 0 && (((u[0] ^ leaf_[0]) | (u[1] ^ leaf_[1]) | (u[2] ^ leaf_[2])) >> 1) == 0) {
        mask_ |= bit;
        continue;
      }
      endRay();
      key_ = cells[i];
      leaf_[0] = u[0], leaf_[1] = u[1], leaf_[2] = u[2];
      mask_ = bit;
    }
  }

  void endRay() {
    if (mask_ == 0) return;
    skip_ = accessor_.setValidLeafCells(key_, mask_, CellState::Free);
    cube_[0] = leaf_[0], cube_[1] = leaf_[1], cube_[2] = leaf_[2];
    mask_ = 0;
  }

  void occupied(const Key& k) { accessor_.setValidCell(k, CellState::Occupied); }

 private:
  Accessor accessor_;
  bool line_burst_;
  Key key_;
  std::uint32_t mask_ = 0, leaf_[3] = {0, 0, 0};  // the pending cells of one leaf
  unsigned skip_ = 0;                             // a cube known free: 2^skip_ cells around cube_
  std::uint32_t cube_[3] = {0, 0, 0};
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
  TreeWriter writer(map, options.line_burst);
  return insert(writer, map.getGrid(), sensor, xyz, count, stride_bytes, options);
}

ScanStats insertRays(FastOccMesh& map, const float sensor[3], const float* xyz, std::size_t count,
                     std::size_t stride_bytes, const ScanOptions& options) {
  GridWriter writer(map);
  return insert(writer, map.getGrid(), sensor, xyz, count, stride_bytes, options);
}

}  // namespace fot
}  // namespace pcl
