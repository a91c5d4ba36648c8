// fot_map: builds a FastOctTree map from range scans with ray tracing; writes it as .fot and for pcl_viewer.
#include <algorithm>
#include <cmath>
#include <cstdint>
#include <cstdio>
#include <cstdlib>
#include <fstream>
#include <sstream>
#include <string>
#include <vector>

#include <pcl/console/print.h>
#include <pcl/console/time.h>

#include <pcl_fot/io/fot_file.h>
#include <pcl_fot/io/voxel_export.h>
#include <pcl_fot/pcl/cloud_insertion.h>
#include <pcl_fot/tree/fast_oct_tree.h>

#include "cloud_file.h"
#include "synthetic_scene.h"
#include "tool_common.h"

using namespace pcl::console;
using namespace fot_tools;
using Cloud = pcl::PointCloud<pcl::PointXYZ>;

namespace {

void printHelp(const char* prog) {
  print_info(
      "Builds a FastOctTree occupancy map from range scans with ray tracing, as OctoMap's insertPointCloud\n"
      "does: each cell along a ray gets a miss and each endpoint a hit, added to the cell's clamped\n"
      "log-odds, and a cell is occupied from the threshold up. With -binary, the paper's rule instead: the\n"
      "cells along every ray become free, the endpoints occupied, and the latest scan wins. Each scan's pose "
      "(sensor in the map frame) is its VIEWPOINT\n"
      "(a PLY file's camera element), or a line of the pose file. Without scans, it maps the embedded\n"
      "default: a synthetic furnished room seen by a depth camera from six poses. Scans whose rays would\n"
      "cross more than 1e10 cells, which usually means a missing pose, are refused before any tracing\n"
      "(cut them with -max_range).\n\n"
      "Syntax: %s [options] [scan1.pcd|.ply scan2.pcd ...]\n\n"
      "  -res <m>          voxel edge length in metres (default: 0.05)\n"
      "  -poses <file>     one pose per scan, in order: tx ty tz qw qx qy qz per line ('#' comments)\n"
      "  -max_range <m>    rays longer than this mark free space up to it and no endpoint (default: none)\n"
      "  -min_range <m>    points closer to the sensor are ignored (default: 0)\n"
      "  -binary           the paper's rule, the latest scan wins, instead of the log-odds\n"
      "  -hit <p>          probability of a hit (default: 0.7), -miss <p> of a miss (default: 0.4)\n"
      "  -clamp_min <p>    clamping thresholds (defaults: 0.1192, 0.971), -clamp_max <p>\n"
      "  -occupancy <p>    occupancy threshold (default: 0.5)\n"
      "  -threads <n>      threads that walk each scan's rays (default: 0, all); the map does not depend on "
      "it\n"
      "  -out <prefix>     output prefix (default: fot_map); writes <prefix>.fot, <prefix>_occupied.pcd\n"
      "                    (voxel centres coloured by height) and <prefix>_mesh.vtk (voxel cubes)\n"
      "  -free             also write <prefix>_states.pcd: occupied and free voxel centres, coloured by "
      "state\n"
      "  -h                this help\n\n"
      "Exit codes: 0 done, 1 bad arguments, 2 a file that cannot be read or written.\n",
      prog);
}

/** Poses from a file: tx ty tz qw qx qy qz per line, as a PCD VIEWPOINT. */
std::vector<Eigen::Affine3f> readPoses(const std::string& path) {
  requireRegularFile(path, "the pose file");
  std::ifstream in(path);
  if (!in) throw ToolError(kExitInput, "cannot read the pose file '" + path + "'");
  std::vector<Eigen::Affine3f> poses;
  std::string line;
  int number = 1;
  for (; readLine(in, line, 4096); ++number) {
    const std::size_t hash = line.find('#');
    if (hash != std::string::npos) line.erase(hash);
    std::istringstream fields(line);
    std::vector<std::string> tokens;
    for (std::string t; fields >> t;) tokens.push_back(t);
    if (tokens.empty()) continue;
    double v[7];
    bool ok = tokens.size() == 7;
    for (std::size_t i = 0; ok && i < 7; ++i) {
      char* end = nullptr;
      v[i] = std::strtod(tokens[i].c_str(), &end);
      ok = *end == '\0' && std::isfinite(v[i]);
    }
    if (!ok)
      throw ToolError(kExitInput, path + ":" + std::to_string(number) +
                                      ": expected 7 finite numbers: tx ty tz qw qx qy qz");
    const Eigen::Quaternionf q{float(v[3]), float(v[4]), float(v[5]), float(v[6])};
    if (!(q.norm() > 1e-6f))
      throw ToolError(kExitInput, path + ":" + std::to_string(number) + ": a zero quaternion");
    poses.push_back(Eigen::Translation3f(float(v[0]), float(v[1]), float(v[2])) * q.normalized());
  }
  if (!in.eof())
    throw ToolError(kExitInput, path + ":" + std::to_string(number) + ": a line that never ends");
  return poses;
}

/** More ray cells than this (about a minute of tracing) is refused: almost always a missing sensor pose. */
constexpr double kMaxRayCells = 1e10;

/**
 * The fewest cells the scan's rays cross: each ray's length in cells, as insertScan clips it. A cloud
 * without a VIEWPOINT far from the origin (georeferenced data, say) would otherwise trace for hours.
 */
double rayCells(const Cloud& scan, double res, const pcl::fot::ScanOptions& options) {
  double cells = 0;
  for (const auto& p : scan) {
    const double length = p.getVector3fMap().cast<double>().norm();
    if (std::isfinite(length) && length >= options.min_range)
      cells += (options.max_range > 0 ? std::min(length, options.max_range) : length) / res;
  }
  return cells;
}

void progress(std::size_t done, std::size_t total, double seconds) {
  const int width = 30, filled = int(width * done / (total ? total : 1));
  std::fprintf(stderr, "\r[%s%s] %zu/%zu scans, %.1f s", std::string(std::size_t(filled), '=').c_str(),
               std::string(std::size_t(width - filled), ' ').c_str(), done, total, seconds);
  if (done == total) std::fprintf(stderr, "\n");
}

/** The sensor of scan i in the map frame: its pose line, or its VIEWPOINT. */
Eigen::Vector3f sensorOf(const std::vector<Cloud::Ptr>& scans, const std::vector<Eigen::Affine3f>& poses,
                         std::size_t i) {
  return poses.empty() ? Eigen::Vector3f(scans[i]->sensor_origin_.head<3>()) : poses[i].translation();
}

/** Refuses, before any tracing, a sensor off the map's keys and rays too long to trace: a bad pose. */
void checkScans(const std::vector<Cloud::Ptr>& scans, const std::vector<Eigen::Affine3f>& poses,
                const pcl::fot::CellGrid& grid, const pcl::fot::ScanOptions& options) {
  double ray_cells = 0;
  for (std::size_t i = 0; i < scans.size(); ++i) {
    const Eigen::Vector3f sensor = sensorOf(scans, poses, i);
    pcl::fot::Key key;
    if (!grid.pointToKey(sensor.x(), sensor.y(), sensor.z(), key)) {
      char where[96];
      std::snprintf(where, sizeof(where), "(%g, %g, %g)", sensor.x(), sensor.y(), sensor.z());
      throw ToolError(kExitInput, "scan " + std::to_string(i + 1) + "'s sensor at " + where +
                                      " is not finite or lies beyond the map's 2^29 cells");
    }
    ray_cells += rayCells(*scans[i], grid.resolution(), options);
    if (ray_cells > kMaxRayCells) {
      char cells[32];
      std::snprintf(cells, sizeof(cells), "%.3g", ray_cells);
      throw ToolError(kExitInput,
                      "the rays up to scan " + std::to_string(i + 1) + " would cross " + cells +
                          " cells (the limit is 1e10): is its sensor pose missing? Give it with "
                          "-poses, cut the rays with -max_range, or map the points alone with fot_convert");
    }
  }
}

/** The sensor model the options give, OctoMap's defaults otherwise. */
pcl::fot::SensorModel sensorModel(const Arguments& args) {
  const pcl::fot::SensorModel defaults;
  double hit = defaults.probHit(), miss = defaults.probMiss(), clamp_min = defaults.clampMin(),
         clamp_max = defaults.clampMax(), occupancy = defaults.occupancy();
  args.get("-hit", hit);
  args.get("-miss", miss);
  args.get("-clamp_min", clamp_min);
  args.get("-clamp_max", clamp_max);
  args.get("-occupancy", occupancy);
  try {
    return pcl::fot::SensorModel(hit, miss, clamp_min, clamp_max, occupancy);
  } catch (const std::invalid_argument& e) {
    throw ToolError(kExitUsage, e.what());
  }
}

/** Traces every scan into the map, with a progress bar; returns the totals. */
pcl::fot::ScanStats mapScans(pcl::fot::FastOctTree& tree, const std::vector<Cloud::Ptr>& scans,
                             const std::vector<Eigen::Affine3f>& poses, const pcl::fot::ScanOptions& options,
                             TicToc& timer) {
  pcl::fot::ScanStats total;
  for (std::size_t i = 0; i < scans.size(); ++i) {
    progress(i, scans.size(), timer.toc() / 1000.0);
    const pcl::fot::ScanStats st = poses.empty() ? pcl::fot::insertScan(tree, *scans[i], options)
                                                 : pcl::fot::insertScan(tree, *scans[i], poses[i], options);
    if (st.rays == 0)
      print_warn("\nScan %zu has no point to trace (%zu NaN/Inf, %zu out of range, %zu too close).\n", i + 1,
                 st.non_finite, st.out_of_range, st.too_close);
    total.rays += st.rays;
    total.non_finite += st.non_finite;
    total.out_of_range += st.out_of_range;
    total.ray_cells += st.ray_cells;
  }
  progress(scans.size(), scans.size(), timer.toc() / 1000.0);
  return total;
}

/** The files fot_map writes for the output prefix `out`. */
std::vector<std::string> outputFiles(const std::string& out, bool with_free) {
  std::vector<std::string> files{out + ".fot", out + "_occupied.pcd", out + "_mesh.vtk"};
  if (with_free) files.push_back(out + "_states.pcd");
  return files;
}

/** Writes the map and its viewer files, and prints what they hold. */
void writeOutputs(const pcl::fot::FastOctTree& tree, const std::string& out, bool with_free,
                  std::size_t scans, const pcl::fot::ScanStats& total) {
  const std::string map_file = out + ".fot", centres_file = out + "_occupied.pcd",
                    mesh_file = out + "_mesh.vtk";
  pcl::fot::io::saveFot(tree, map_file);
  const std::size_t centres = pcl::fot::io::saveVoxelCentersPCD(tree, centres_file);
  const std::size_t faces = pcl::fot::io::saveVoxelMeshVTK(tree, mesh_file);

  print_info("Map summary\n");
  print_info("  scans              %zu\n", scans);
  print_info("  rays traced        %zu through %llu cells (skipped: %zu NaN/Inf, %zu out of range)\n",
             total.rays, (unsigned long long)total.ray_cells, total.non_finite, total.out_of_range);
  print_info("  resolution         %g m\n", tree.getResolution());
  print_info("  depth              %u levels\n", tree.getDepth());
  print_info("  update rule        %s\n", tree.getUpdateRule() == pcl::fot::UpdateRule::LogOdds
                                              ? "log-odds (OctoMap's sensor model)"
                                              : "binary (the latest scan wins)");
  print_info("  occupied cells     %llu\n", (unsigned long long)tree.getOccupiedCount());
  print_info("  free cells         %llu\n", (unsigned long long)tree.getFreeCount());
  print_info("  unsettled cells    %llu (log-odds between the clamps)\n",
             (unsigned long long)tree.getUnsettledCount());
  print_info("  node words         %zu in %zu blocks\n", tree.getNodeCount(), tree.getBlockCount());
  print_info("  memory             %zu bytes\n", tree.getMemoryBytes());
  print_info("Wrote %s (the map), %s (%zu voxel centres) and %s (%zu faces)\n", map_file.c_str(),
             centres_file.c_str(), centres, mesh_file.c_str(), faces);
  if (with_free) {
    pcl::fot::io::VoxelExportOptions free_only;
    free_only.include_free = true;
    free_only.coloring = pcl::fot::io::VoxelColoring::State;
    const std::string free_file = out + "_states.pcd";
    print_info("Wrote %s (%zu voxel centres, occupied and free)\n", free_file.c_str(),
               pcl::fot::io::saveVoxelCentersPCD(tree, free_file, free_only));
  }
  print_info("View them with: pcl_viewer %s   or   pcl_viewer %s\n", centres_file.c_str(), mesh_file.c_str());
}

}  // namespace

int main(int argc, char** argv) {
  return runTool("fot_map", "fot_map [options] [scan1.pcd|.ply scan2.pcd ...]", [&] {
    const Arguments args(argc, argv,
                         {"-res", "-poses", "-max_range", "-min_range", "-out", "-hit", "-miss", "-clamp_min",
                          "-clamp_max", "-occupancy", "-threads"},
                         {"-free", "-binary", "-h", "--help"});
    if (args.helpAsked()) {
      printHelp("fot_map");
      return kExitOk;
    }
    double res = 0.05;
    std::string out = "fot_map", pose_file;
    pcl::fot::ScanOptions options;
    args.getResolution(res);
    args.getPositive("-max_range", options.max_range);
    if (args.get("-min_range", options.min_range) && options.min_range < 0)
      throw ToolError(kExitUsage, "option -min_range must not be negative");
    int threads = 0;
    if (args.get("-threads", threads)) {
      if (threads < 0) throw ToolError(kExitUsage, "option -threads must not be negative");
      options.threads = unsigned(threads);
    }
    args.get("-out", out);
    const bool with_poses = args.get("-poses", pose_file);
    requireWritableDirectory(out + ".fot");
    std::vector<std::string> inputs = args.positional(), outputs = outputFiles(out, args.has("-free"));
    if (with_poses) inputs.push_back(pose_file);
    refuseOverwrites(inputs, outputs);

    TicToc timer;
    timer.tic();
    std::vector<Cloud::Ptr> scans;
    if (args.positional().empty()) {
      print_info("No scans given: mapping the embedded synthetic room.\n");
      scans = scanSyntheticRoom();
    }
    for (const std::string& file : args.positional()) scans.push_back(loadCloud(file));
    std::vector<Eigen::Affine3f> poses;
    if (with_poses) {
      poses = readPoses(pose_file);
      if (poses.size() != scans.size())
        throw ToolError(kExitInput, "the pose file has " + std::to_string(poses.size()) + " poses for " +
                                        std::to_string(scans.size()) + " scans");
    }
    const pcl::fot::CellGrid grid(res);
    checkScans(scans, poses, grid, options);
    pcl::fot::FastOctTree tree(grid);
    tree.setSensorModel(sensorModel(args));
    tree.setUpdateRule(args.has("-binary") ? pcl::fot::UpdateRule::Binary : pcl::fot::UpdateRule::LogOdds);
    const pcl::fot::ScanStats total = mapScans(tree, scans, poses, options, timer);
    writeOutputs(tree, out, args.has("-free"), scans.size(), total);
    print_info("Done in %.0f ms\n", timer.toc());
    return kExitOk;
  });
}
