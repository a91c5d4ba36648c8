#pragma once

#include <string>
#include <vector>

#include "bench_scans.h"

namespace fot_bench {

/** Each section runs its experiment side by side in one process and returns Markdown. */
std::string benchCellAccess(const std::vector<BenchScan>& scans, int repeats);
std::string benchRayTracing(const std::vector<BenchScan>& scans, int repeats);
std::string benchSearch(const std::vector<BenchScan>& scans, int repeats);

}  // namespace fot_bench
