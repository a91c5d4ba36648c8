// fot_info: what a map holds: grid, extent, depth, cells by state, nodes and bytes.
#include <algorithm>
#include <string>

#include <pcl/console/print.h>

#include "tool_common.h"

using namespace pcl::console;
using namespace fot_tools;

namespace {

void printHelp(const char* prog) {
  print_info(
      "Prints what maps hold: resolution, origin, the extent of their known cells, depth, cell counts by\n"
      "state, node words and bytes.\n\n"
      "Syntax: %s map.fot|map.bt|map.ot|tile set [more maps ...]\n\n"
      "A tile set (the directory or tiles.json of python3 -m pcl_fot.tiles) is read as one map.\n\n"
      "  -max_memory <MiB>  the most memory a map may take (default: 1024); a file that needs more is\n"
      "                     refused at once\n"
      "  -h                 this help\n\n"
      "Exit codes: 0 done, 1 bad arguments, 2 a file that cannot be read or is not a valid map.\n",
      prog);
}

void describe(const std::string& path, std::size_t max_bytes) {
  const pcl::fot::FastOctTree tree = loadMap(path, max_bytes);
  const pcl::fot::CellGrid& grid = tree.getGrid();
  print_info("%s\n", path.c_str());
  print_info("  resolution      %.17g m\n", grid.resolution());
  print_info("  origin          %.17g %.17g %.17g\n", grid.origin()[0], grid.origin()[1], grid.origin()[2]);
  if (tree.empty()) {
    print_info("  extent          empty\n");
  } else {
    pcl::fot::Key lo{pcl::fot::kMaxKey, pcl::fot::kMaxKey, pcl::fot::kMaxKey};
    pcl::fot::Key hi{pcl::fot::kMinKey, pcl::fot::kMinKey, pcl::fot::kMinKey};
    tree.forEachRegion([&](const pcl::fot::Region& r) {
      const std::int32_t last = std::int32_t((std::int64_t(1) << r.level) - 1);
      lo = {std::min(lo.x, r.min_key.x), std::min(lo.y, r.min_key.y), std::min(lo.z, r.min_key.z)};
      hi = {std::max(hi.x, r.min_key.x + last), std::max(hi.y, r.min_key.y + last),
            std::max(hi.z, r.min_key.z + last)};
    });
    const double res = grid.resolution();
    print_info("  extent (keys)   %d %d %d  to  %d %d %d\n", lo.x, lo.y, lo.z, hi.x, hi.y, hi.z);
    print_info("  extent (m)      %.3f %.3f %.3f  to  %.3f %.3f %.3f\n", grid.origin()[0] + lo.x * res,
               grid.origin()[1] + lo.y * res, grid.origin()[2] + lo.z * res,
               grid.origin()[0] + (hi.x + 1) * res, grid.origin()[1] + (hi.y + 1) * res,
               grid.origin()[2] + (hi.z + 1) * res);
  }
  print_info("  depth           %u levels\n", tree.getDepth());
  const pcl::fot::SensorModel& m = tree.getSensorModel();
  print_info("  update rule     %s\n",
             tree.getUpdateRule() == pcl::fot::UpdateRule::LogOdds ? "log-odds" : "binary");
  print_info("  sensor model    hit %g, miss %g, clamps %g and %g, occupancy threshold %g\n", m.probHit(),
             m.probMiss(), m.clampMin(), m.clampMax(), m.occupancy());
  print_info("  occupied cells  %llu\n", (unsigned long long)tree.getOccupiedCount());
  print_info("  free cells      %llu\n", (unsigned long long)tree.getFreeCount());
  const std::uint64_t unsettled = tree.getUnsettledCount();
  print_info("  settled cells   %llu (at a clamp)\n",
             (unsigned long long)(tree.getOccupiedCount() + tree.getFreeCount() - unsettled));
  print_info("  unsettled cells %llu (log-odds between the clamps, in %zu words)\n",
             (unsigned long long)unsettled, tree.getValueLeafCount());
  print_info("  node words      %zu in %zu blocks\n", tree.getNodeCount(), tree.getBlockCount());
  print_info("  bytes           %zu in memory\n", tree.getMemoryBytes());
}

}  // namespace

int main(int argc, char** argv) {
  return runTool("fot_info", "fot_info map.fot|map.bt|map.ot [more maps ...]", [&] {
    const Arguments args(argc, argv, {"-max_memory"}, {"-h", "--help"}, 1);
    if (args.helpAsked()) {
      printHelp("fot_info");
      return kExitOk;
    }
    const std::size_t max_bytes = maxMemory(args);
    for (const std::string& path : args.positional()) describe(path, max_bytes);
    return kExitOk;
  });
}
