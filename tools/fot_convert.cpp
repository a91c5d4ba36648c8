// fot_convert: converts maps between .fot, OctoMap .bt and .ot, voxel-centre .pcd and .vtk cube meshes.
#include <cmath>
#include <string>

#include <pcl/common/point_tests.h>
#include <pcl/console/print.h>
#include <pcl/console/time.h>

#include <pcl_fot/io/fot_file.h>
#include <pcl_fot/io/octomap.h>
#include <pcl_fot/io/voxel_export.h>
#include <pcl_fot/pcl/cloud_insertion.h>

#include "cloud_file.h"
#include "tile_set.h"
#include "tool_common.h"

using namespace pcl::console;
using namespace fot_tools;

namespace {

void printHelp(const char* prog) {
  print_info(
      "Converts a map, or builds one from a point cloud, by the files' extensions.\n\n"
      "Syntax: %s input output [options]\n\n"
      "  input   .fot (pcl_fot map), .bt or .ot (OctoMap binary or full map), a tile set (the directory\n"
      "          or tiles.json of python3 -m pcl_fot.tiles: its tiles as one map), or .pcd / .ply (a point\n"
      "          cloud: its points become occupied cells, no ray tracing; needs -res)\n"
      "  output  .fot, .bt (OctoMap's maximum-likelihood map), .ot (OctoMap's full map, with every\n"
      "          log-odds), .pcd (voxel centres for pcl_viewer) or .vtk (voxel cube mesh for pcl_viewer)\n\n"
      "  -res <m>            voxel edge for a point cloud input\n"
      "  -origin <x,y,z>     map origin for a point cloud, .bt or .ot input (default: 0,0,0); for OctoMap\n"
      "                      maps, a whole number of cells from 0 on each axis\n"
      "  -free               .pcd and .vtk outputs: free voxels as well as occupied ones\n"
      "  -color <mode>       .pcd and .vtk outputs: height (default), state, or none (.pcd only)\n"
      "  -max_memory <MiB>   the most memory a map may take (default: 1024); a file that needs more, or an\n"
      "                      OctoMap export that would, is refused at once\n"
      "  -h                  this help\n\n"
      "Exit codes: 0 done, 1 bad arguments, 2 a file that cannot be read, is not valid, or cannot be\n"
      "written, or a map the output format cannot hold.\n",
      prog);
}

/** -color, for an output of extension `out_ext`. */
pcl::fot::io::VoxelColoring coloring(const Arguments& args, const std::string& out_ext) {
  std::string color = "height";
  args.get("-color", color);
  if (color == "height") return pcl::fot::io::VoxelColoring::Height;
  if (color == "state") return pcl::fot::io::VoxelColoring::State;
  if (color == "none" && out_ext == ".pcd") return pcl::fot::io::VoxelColoring::None;
  throw ToolError(kExitUsage, "option -color takes height, state or none (.pcd only)");
}

/**
 * Says why points lie beyond the keys, which reach 2^29 cells either side of the origin, and what can work:
 * a coarser resolution when the cloud is wider than the keys reach, else an origin at its centre
 * (georeferenced data, usually).
 */
void adviseOnRange(const pcl::PointCloud<pcl::PointXYZ>& cloud, double res, std::size_t beyond) {
  Eigen::Vector3d lo = Eigen::Vector3d::Constant(INFINITY), hi = -lo;
  for (const auto& p : cloud)
    if (pcl::isFinite(p)) {
      lo = lo.cwiseMin(p.getVector3fMap().cast<double>());
      hi = hi.cwiseMax(p.getVector3fMap().cast<double>());
    }
  // An origin at the centre, on the grid, holds the cloud if it spans 2^30 cells less the rounding.
  const double span = (hi - lo).maxCoeff();
  if (!(span <= std::ldexp(res, 30) - 2 * res)) {
    print_warn(
        "%zu points lie beyond the map's cells: the cloud spans %g m, more than the 2^30 cells of %g m a map "
        "holds per axis; give a coarser -res (%g m or more)\n",
        beyond, span, res, std::ldexp(span, -30) * 1.01);
    return;
  }
  double origin[3];
  for (int a = 0; a < 3; ++a)
    origin[a] = std::round((lo[a] + hi[a]) / 2 / res) * res + 0.0;  // + 0.0: no "-0"
  print_warn(
      "%zu points lie beyond 2^29 cells of the origin: centre the map on the cloud with -origin "
      "%.12g,%.12g,%.12g\n",
      beyond, origin[0], origin[1], origin[2]);
}

/** A map of a point cloud's points, no ray tracing; names an origin that fits when points lie beyond it. */
pcl::fot::FastOctTree mapOfCloud(const std::string& input, const Arguments& args,
                                 const std::vector<double>& origin) {
  double res = 0;
  if (!args.getResolution(res)) throw ToolError(kExitUsage, "a point cloud input needs -res (see -h)");
  const std::string bad_grid = pcl::fot::CellGrid::whyInvalid(res, origin[0], origin[1], origin[2]);
  if (!bad_grid.empty()) throw ToolError(kExitUsage, "options -res and -origin: " + bad_grid);
  const auto cloud = loadCloud(input);
  pcl::fot::FastOctTree tree(pcl::fot::CellGrid(res, origin[0], origin[1], origin[2]));
  const pcl::fot::InsertStats st = pcl::fot::insertPointCloud(tree, *cloud);
  print_info("Inserted %zu points (skipped %zu NaN/Inf, %zu out of range)\n", st.inserted, st.non_finite,
             st.out_of_range);
  if (st.out_of_range > 0) adviseOnRange(*cloud, res, st.out_of_range);
  return tree;
}

/** The input map, by its extension, of at most max_bytes. */
pcl::fot::FastOctTree readInput(const std::string& input, const Arguments& args,
                                const std::vector<double>& origin, std::size_t max_bytes) {
  if (isTileSet(input)) return loadTileSet(input, max_bytes);
  const std::string in_ext = extension(input);
  if (in_ext == ".pcd" || in_ext == ".ply") return mapOfCloud(input, args, origin);
  if (in_ext == ".bt" || in_ext == ".ot") {
    pcl::fot::io::OctoMapImportOptions options;
    std::copy(origin.begin(), origin.end(), options.origin);
    options.max_pool_bytes = max_bytes;
    return in_ext == ".bt" ? pcl::fot::io::loadBt(input, options) : pcl::fot::io::loadOt(input, options);
  }
  if (in_ext == ".fot") return pcl::fot::io::loadFot(input, max_bytes);
  throw ToolError(kExitUsage,
                  "cannot read '" + input + "': the input must be .fot, .bt, .ot, .pcd, .ply or a tile set");
}

/** Writes the map by the output's extension; returns what was written. */
std::string writeOutput(const pcl::fot::FastOctTree& tree, const std::string& output,
                        const std::string& out_ext, const pcl::fot::io::VoxelExportOptions& exported,
                        std::size_t max_bytes) {
  if (out_ext == ".fot") {
    pcl::fot::io::saveFot(tree, output);
    return "map";
  }
  if (out_ext == ".bt") {
    pcl::fot::io::saveBt(tree, output, max_bytes);
    return "OctoMap map";
  }
  if (out_ext == ".ot") {
    pcl::fot::io::saveOt(tree, output, max_bytes);
    return "OctoMap map with its log-odds";
  }
  if (out_ext == ".pcd")
    return std::to_string(pcl::fot::io::saveVoxelCentersPCD(tree, output, exported)) + " voxel centres";
  return std::to_string(pcl::fot::io::saveVoxelMeshVTK(tree, output, exported)) + " cube faces";
}

}  // namespace

int main(int argc, char** argv) {
  return runTool("fot_convert", "fot_convert input output [options]", [&] {
    const Arguments args(argc, argv, {"-res", "-origin", "-color", "-max_memory"}, {"-free", "-h", "--help"},
                         2, 2);
    if (args.helpAsked()) {
      printHelp("fot_convert");
      return kExitOk;
    }
    const std::string &input = args.positional()[0], &output = args.positional()[1];
    refuseOverwrites(isTileSet(input) ? tileSetFiles(input) : std::vector<std::string>{input}, {output});
    const std::string out_ext = extension(output);
    if (out_ext != ".fot" && out_ext != ".bt" && out_ext != ".ot" && out_ext != ".pcd" && out_ext != ".vtk")
      throw ToolError(kExitUsage,
                      "cannot write '" + output + "': the output must be .fot, .bt, .ot, .pcd or .vtk");
    requireWritableDirectory(output);
    std::vector<double> origin{0, 0, 0};
    args.get("-origin", origin, 3);
    pcl::fot::io::VoxelExportOptions exported;
    exported.include_free = args.has("-free");
    exported.coloring = coloring(args, out_ext);
    const std::size_t max_bytes = maxMemory(args);

    TicToc timer;
    timer.tic();
    const pcl::fot::FastOctTree tree = readInput(input, args, origin, max_bytes);
    const std::string what = writeOutput(tree, output, out_ext, exported, max_bytes);
    print_info("Wrote %s (%s: %llu occupied, %llu free cells) in %.0f ms\n", output.c_str(), what.c_str(),
               (unsigned long long)tree.getOccupiedCount(), (unsigned long long)tree.getFreeCount(),
               timer.toc());
    return kExitOk;
  });
}
