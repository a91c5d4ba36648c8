// Fuzz target: ray-traced scan insertion with arbitrary floats: NaN, Inf, huge and denormal values. The
// input is a resolution choice, a max-range choice, the sensor position and the points. Bad points must be
// skipped and counted; the tree must come out canonical, the same with and without LineBurstAccess.
#include <cmath>
#include <cstdint>
#include <cstdlib>
#include <cstring>
#include <stdexcept>
#include <vector>

#include <pcl_fot/scan_insertion.h>

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
  if (with.getNodeCount() < 200000) {
    const pcl::fot::FastOctTree rebuilt =
        pcl::fot::FastOctTree::fromCanonicalPool(with.getGrid(), with.canonicalPool());
    if (!(rebuilt == with)) std::abort();
  }
  return 0;
}
