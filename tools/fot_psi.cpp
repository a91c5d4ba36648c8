// fot_psi: the map similarity ψ of two point clouds or maps, with an optional transform of the first.
#include <cstdio>
#include <optional>
#include <string>

#include <pcl/common/transforms.h>
#include <pcl/console/print.h>
#include <pcl/console/time.h>

#include <pcl_fot/pcl/cloud_insertion.h>
#include <pcl_fot/psi/psi.h>

#include "cloud_file.h"
#include "tool_common.h"

using namespace pcl::console;
using namespace fot_tools;
using Cloud = pcl::PointCloud<pcl::PointXYZ>;

namespace {

void printHelp(const char* prog) {
  print_info(
      "Scores how well two maps agree with the map similarity psi (Poppinga et al. 2007, eqs. 1-2): the sum\n"
      "over both maps' cells of the Manhattan distance, in cells, to the nearest cell of the other map with\n"
      "the same state. 0 for equal maps; lower is better.\n\n"
      "Syntax: %s a b [options]\n\n"
      "  a, b                 .pcd / .ply point clouds (their points become occupied cells at -res) or\n"
      "                       .fot / .bt / .ot maps (of the same grid)\n"
      "  -res <m>             voxel edge for point clouds (default: a map's grid beside a map, else 0.05;\n"
      "                       maps keep their own)\n"
      "  -transform <tx,ty,tz,roll,pitch,yaw>  moves a (a point cloud) first: rotations in radians about\n"
      "                       x, y, z, applied in that order, then the translation\n"
      "  -free                compare free cells too (V = {occupied, free}); point clouds have none\n"
      "  -cap <cells>         each cell's distance counts at most this many cells\n"
      "  -threads <n>         worker threads (default: 0, all); the result does not depend on it\n"
      "  -max_memory <MiB>    the most memory a map may take (default: 1024); a file that needs more is\n"
      "                       refused at once\n"
      "  -h                   this help\n\n"
      "Exit codes: 0 done, 1 bad arguments, 2 a file that cannot be read, or maps of different grids.\n",
      prog);
}

/** "0.05 m cells from (0, 0, 0)" */
std::string describe(const pcl::fot::CellGrid& grid) {
  char text[160];
  std::snprintf(text, sizeof text, "%.9g m cells from (%.9g, %.9g, %.9g)", grid.resolution(),
                grid.origin()[0], grid.origin()[1], grid.origin()[2]);
  return text;
}

/**
 * Reports the points of a cloud that did not become cells, and refuses a cloud that kept fewer than half
 * of them: ψ would describe a remnant, and read as a good score.
 */
void checkKept(const char* which, const std::string& path, std::size_t points,
               const pcl::fot::InsertStats& st) {
  const std::size_t dropped = st.non_finite + st.out_of_range;
  if (dropped == 0) return;
  print_warn("%s ('%s'): %zu of %zu points dropped (%zu NaN/Inf, %zu beyond the map's 2^29 cells)\n", which,
             path.c_str(), dropped, points, st.non_finite, st.out_of_range);
  if (st.inserted < st.out_of_range)
    throw ToolError(kExitInput, std::string(which) + " ('" + path + "') keeps " +
                                    std::to_string(st.inserted) + " of its " +
                                    std::to_string(st.inserted + st.out_of_range) +
                                    " finite points; the rest lie beyond the map's cells (a coarser -res "
                                    "reaches further): psi of the remnant would mislead");
}

}  // namespace

int main(int argc, char** argv) {
  return runTool("fot_psi", "fot_psi a b [options]", [&] {
    const Arguments args(argc, argv, {"-res", "-transform", "-cap", "-threads", "-max_memory"},
                         {"-free", "-h", "--help"}, 2, 2);
    if (args.helpAsked()) {
      printHelp("fot_psi");
      return kExitOk;
    }
    double res = 0.05;
    args.getResolution(res);
    pcl::fot::PsiOptions options;
    options.include_free = args.has("-free");
    options.threads = 0;
    int cap = -1, threads = 0;
    if (args.get("-cap", cap)) {
      if (cap < 0) throw ToolError(kExitUsage, "option -cap must not be negative");
      options.cap = cap;
    }
    if (args.get("-threads", threads)) {
      if (threads < 0) throw ToolError(kExitUsage, "option -threads must not be negative");
      options.threads = unsigned(threads);
    }
    std::vector<double> t;
    const bool transformed = args.get("-transform", t, 6, true);

    // A point cloud takes the grid of a map beside it, unless -res is given; two clouds take -res.
    const std::string paths[2] = {args.positional()[0], args.positional()[1]};
    std::optional<pcl::fot::FastOctTree> maps[2];
    const std::size_t max_bytes = maxMemory(args);
    for (int i = 0; i < 2; ++i)
      if (isMapFile(paths[i])) maps[i] = loadMap(paths[i], max_bytes);
    if (maps[0] && transformed) throw ToolError(kExitUsage, "-transform moves a point cloud, and a is a map");
    pcl::fot::CellGrid cloud_grid(res);
    if (!args.has("-res") && (maps[0] || maps[1])) cloud_grid = (maps[0] ? maps[0] : maps[1])->getGrid();
    for (int i = 0; i < 2; ++i) {
      if (maps[i]) continue;
      const Cloud::Ptr cloud = loadCloud(paths[i]);
      if (i == 0 && transformed) {
        const Eigen::Affine3f pose = Eigen::Translation3f(float(t[0]), float(t[1]), float(t[2])) *
                                     Eigen::AngleAxisf(float(t[5]), Eigen::Vector3f::UnitZ()) *
                                     Eigen::AngleAxisf(float(t[4]), Eigen::Vector3f::UnitY()) *
                                     Eigen::AngleAxisf(float(t[3]), Eigen::Vector3f::UnitX());
        pcl::transformPointCloud(*cloud, *cloud, pose);
      }
      maps[i].emplace(cloud_grid);
      checkKept(i == 0 ? "a" : "b", paths[i], cloud->size(), pcl::fot::insertPointCloud(*maps[i], *cloud));
    }
    const pcl::fot::FastOctTree &a = *maps[0], &b = *maps[1];
    if (a.getGrid() != b.getGrid())
      throw ToolError(kExitInput, "the maps must share their grid: a has " + describe(a.getGrid()) + ", b " +
                                      describe(b.getGrid()));
    for (int i = 0; i < 2; ++i)
      if (maps[i]->getOccupiedCount() == 0)
        throw ToolError(kExitInput, std::string(i == 0 ? "a" : "b") + " ('" + paths[i] +
                                        "') has no occupied cell: there is nothing to compare");
    TicToc timer;
    timer.tic();
    const pcl::fot::PsiResult r = pcl::fot::psi(a, b, options);
    const double ms = timer.toc();
    print_info("psi        %llu cells%s\n", (unsigned long long)r.sum,
               r.defined ? "" : " (undefined: one map lacks a compared state; this sums the rest)");
    print_info("cells      %llu compared (%llu and %llu occupied%s)\n", (unsigned long long)r.cells,
               (unsigned long long)a.getOccupiedCount(), (unsigned long long)b.getOccupiedCount(),
               options.include_free ? ", plus free" : "");
    print_info("mean       %.6f cells = %.6f m per cell\n", r.mean(), r.meanMetres());
    print_info("time       %.2f ms\n", ms);
    return kExitOk;
  });
}
