// Fuzz target: ray-traced scan insertion with arbitrary floats: NaN, Inf, huge and denormal values. The
// input is a resolution choice, a max-range choice, the sensor position and the points. Bad points must be
// skipped and counted; the tree must come out canonical, the same with and without LineBurstAccess. Without
// range limits it must hold exactly the cells of each ray's plain DDA walk, as must a grid around the sensor.
#include <cmath>
#include <cstdint>
#include <cstdlib>
#include <cstring>
#include <stdexcept>
#include <unordered_map>
#include <vector>

#include <pcl_fot/mapping/ray_traversal.h>
#include <pcl_fot/mapping/scan_insertion.h>

namespace {

using pcl::fot::CellState;
using pcl::fot::Key;

/**
 * Without range limits, each ray frees the cells traceSegment walks, and then its end cell is occupied:
 * the tree, which walks the rays a block at a time, must hold exactly those cells, and a grid around the
 * sensor the same ones within it.
 */
void checkAgainstSegments(const pcl::fot::FastOctTree& tree, const float sensor[3],
                          const std::vector<float>& xyz, const pcl::fot::ScanStats& stats) {
  const pcl::fot::CellGrid& grid = tree.getGrid();
  std::unordered_map<Key, CellState, pcl::fot::KeyHash> cells;
  std::vector<Key> ends;
  std::size_t rays = 0;
  for (std::size_t i = 0; i < xyz.size(); i += 3) {
    Key end;
    if (!grid.pointToKey(xyz[i], xyz[i + 1], xyz[i + 2], end)) continue;
    // Rays may step a cell past their ends: both ends keep a cell inside the key range.
    const auto inside = [](std::int32_t k) { return k > pcl::fot::kMinKey && k < pcl::fot::kMaxKey; };
    if (!inside(end.x) || !inside(end.y) || !inside(end.z)) continue;
    ++rays;
    ends.push_back(end);
    pcl::fot::traceSegment(grid, sensor, &xyz[i], [&](const Key& k) { cells[k] = CellState::Free; });
  }
  for (const Key& k : ends) cells[k] = CellState::Occupied;
  if (rays != stats.rays) std::abort();
  std::size_t held = 0;
  for (CellState s : {CellState::Free, CellState::Occupied})
    tree.forEachCell(s, [&](const Key& k) {
      const auto it = cells.find(k);
      if (it == cells.end() || it->second != s) std::abort();
      ++held;
    });
  if (held != cells.size()) std::abort();

  Key centre;
  if (!grid.pointToKey(sensor[0], sensor[1], sensor[2], centre)) std::abort();
  const Key lo{centre.x - 16, centre.y - 16, centre.z - 16};
  if (!pcl::fot::isValidKey(lo) || !pcl::fot::isValidKey(Key{lo.x + 31, lo.y + 31, lo.z + 31})) return;
  pcl::fot::FastOccMesh mesh(grid, 32, lo);
  pcl::fot::insertRays(mesh, sensor, xyz.data(), xyz.size() / 3, 12);
  for (std::int32_t z = 0; z < 32; ++z)
    for (std::int32_t y = 0; y < 32; ++y)
      for (std::int32_t x = 0; x < 32; ++x) {
        const Key k{lo.x + x, lo.y + y, lo.z + z};
        if (mesh.getCell(k) != tree.getCell(k)) std::abort();
      }
}

}  // namespace

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
  if (size < 2 + 12) return 0;
  static const double kResolutions[] = {0.01, 0.05, 0.1, 1.0};
  static const double kRanges[] = {-1.0, 0.5, 5.0, 50.0};
  pcl::fot::ScanOptions options;
  const double res = kResolutions[data[0] & 3];
  options.max_range = kRanges[(data[0] >> 2) & 3];
  options.min_range = (data[0] & 0x10) ? 0.2 : 0.0;
  float sensor[3];
  std::memcpy(sensor, data + 2, 12);
  std::vector<float> xyz((size - 14) / 12 * 3);
  if (!xyz.empty()) std::memcpy(xyz.data(), data + 14, xyz.size() * sizeof(float));
  const std::size_t count = xyz.size() / 3;

  pcl::fot::FastOctTree with(res), without(res);
  // A ray can cross 2^30 cells; the cap stops one quickly, which keeps the fuzzer fast.
  with.setMaxMemoryBytes(std::size_t(512) << 10);
  without.setMaxMemoryBytes(std::size_t(512) << 10);
  pcl::fot::ScanOptions plain = options;
  plain.line_burst = false;
  int outcome[2] = {0, 0};  // 0 done, 1 refused sensor, 2 past the memory cap
  pcl::fot::ScanStats stats;
  for (int pass = 0; pass < 2; ++pass) {
    try {
      stats =
          pcl::fot::insertRays(pass ? without : with, sensor, xyz.data(), count, 12, pass ? plain : options);
    } catch (const std::invalid_argument&) {  // a sensor position that is not finite
      outcome[pass] = 1;
    } catch (const std::out_of_range&) {  // a sensor beyond the key range
      outcome[pass] = 1;
    } catch (const pcl::fot::MemoryLimitError&) {
      outcome[pass] = 2;
    }
  }
  if (outcome[0] != outcome[1]) std::abort();
  if (outcome[0] == 1 && (std::isfinite(sensor[0]) && std::isfinite(sensor[1]) && std::isfinite(sensor[2])) &&
      std::fabs(sensor[0]) < 1e6f && std::fabs(sensor[1]) < 1e6f && std::fabs(sensor[2]) < 1e6f)
    std::abort();  // a sensor well inside the key range must be accepted
  if (outcome[0] != 0) return 0;
  if (stats.rays + stats.non_finite + stats.out_of_range + stats.too_close != count) std::abort();
  if (stats.occupied > stats.rays) std::abort();
  if (!(with == without)) std::abort();
  if (options.max_range <= 0.0 && options.min_range == 0.0 && stats.ray_cells < 4'000'000)
    checkAgainstSegments(with, sensor, xyz, stats);
  if (with.getNodeCount() < 200000) {
    const pcl::fot::FastOctTree rebuilt =
        pcl::fot::FastOctTree::fromCanonicalPool(with.getGrid(), with.canonicalPool());
    if (!(rebuilt == with)) std::abort();
  }
  return 0;
}
