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

struct TreeWriter {
  TreeWriter(FastOctTree& t, bool line_burst) : accessor(t, line_burst) {}
  void set(const Key& k, CellState s) { accessor.setValidCell(k, s); }
  Accessor accessor;
};

struct GridWriter {
  void set(const Key& k, CellState s) {
    if (grid.contains(k)) grid.setCell(k, s);
  }
  FastOccMesh& grid;
};

/** A ray may step one cell past its end keys; keep those cells inside the key range too. */
bool traceable(const Key& k) {
  return k.x > kMinKey && k.x < kMaxKey && k.y > kMinKey && k.y < kMaxKey && k.z > kMinKey && k.z < kMaxKey;
}

template <typename Writer>
ScanStats insert(Writer& writer, const VoxelGrid& grid, const float sensor[3], const float* xyz, std::size_t count,
                 std::size_t stride_bytes, const ScanOptions& options) {
  if (!std::isfinite(sensor[0]) || !std::isfinite(sensor[1]) || !std::isfinite(sensor[2]))
    throw std::invalid_argument("pcl::fot::insertRays: the sensor position is not finite");
  Key sensor_key;
  if (!grid.pointToKey(sensor[0], sensor[1], sensor[2], sensor_key) || !traceable(sensor_key))
    throw std::out_of_range("pcl::fot::insertRays: the sensor lies beyond the key range");

  ScanStats stats;
  std::vector<Key> endpoints;
  endpoints.reserve(count);
  auto mark_free = [&](const Key& k) {
    writer.set(k, CellState::Free);
    ++stats.cells_written;
  };
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
      traceSegment(grid, sensor, end, mark_free);
      ++stats.truncated;
      ++stats.rays;
      continue;
    }
    Key key;
    if (!grid.pointToKey(p[0], p[1], p[2], key) || !traceable(key)) {
      ++stats.out_of_range;
      continue;
    }
    traceSegment(grid, sensor, p, mark_free);
    endpoints.push_back(key);
    ++stats.rays;
  }
  // Endpoints last: within a scan, occupied wins over free.
  for (const Key& k : endpoints) writer.set(k, CellState::Occupied);
  stats.occupied = endpoints.size();
  stats.cells_written += endpoints.size();
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
  GridWriter writer{map};
  return insert(writer, map.getGrid(), sensor, xyz, count, stride_bytes, options);
}

}  // namespace fot
}  // namespace pcl
