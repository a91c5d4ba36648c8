// fot_icp_psi: runs pcl::IterativeClosestPoint and scores every iteration with ψ, next to ICP's own fitness.
#include <algorithm>
#include <iterator>
#include <string>
#include <vector>

#include <pcl/common/point_tests.h>
#include <pcl/console/parse.h>
#include <pcl/console/print.h>
#include <pcl/console/time.h>
#include <pcl/filters/voxel_grid.h>
#include <pcl/registration/icp.h>

#include <pcl_fot/pcl/registration/correspondence_rejection_psi.h>
#include <pcl_fot/pcl/registration/transformation_validation_psi.h>

#include "cloud_file.h"
#include "tool_common.h"

using namespace pcl::console;
using namespace fot_tools;
using Cloud = pcl::PointCloud<pcl::PointXYZ>;

namespace {

constexpr int kExitNotConverged = 3;

void printHelp(const char* prog) {
  print_info(
      "Aligns a source scan to a target scan with pcl::IterativeClosestPoint and prints, at the initial "
      "guess,\n"
      "at every iteration and at convergence, the map similarity psi (mean Manhattan distance per occupied\n"
      "cell, in metres, each cell counting at most -max_range) next to ICP's getFitnessScore (mean squared\n"
      "distance of source points to their nearest target point).\n\n"
      "Syntax: %s source.pcd|.ply target.pcd|.ply [options]\n\n"
      "  -guess <tx,ty,tz,yaw>  initial guess: a rotation of yaw radians about z, then a translation "
      "(default: 0,0,0,0)\n"
      "  -leaf <m>              voxel-grid leaf both scans are downsampled with first (default: 0.1; 0: "
      "none)\n"
      "  -res <m>               psi's voxel edge (default: 0.1)\n"
      "  -max_range <m>         the most one cell's psi distance counts (default: 1)\n"
      "  -max_corr <m>          ICP's maximum correspondence distance (default: 0.5)\n"
      "  -iterations <n>        ICP's maximum iterations (default: 50)\n"
      "  -h                     this help\n\n"
      "Exit codes: 0 converged, 1 bad arguments, 2 a file that cannot be read, 3 ICP did not converge.\n\n"
      "Example, PCL's NDT tutorial pair from its initial guess:\n"
      "  %s room_scan2.pcd room_scan1.pcd -guess 1.79387,0.720047,0,0.6931\n",
      prog, prog);
}

/**
 * A scan's finite points, downsampled with a voxel grid if leaf > 0. PCL's ICP must not see the NaN points
 * of an organised cloud (its kd-tree asserts on them), nor a cloud without finite points (it would crash in
 * getFitnessScore).
 */
Cloud::Ptr registrationInput(const std::string& file, float leaf) {
  const Cloud::Ptr loaded = loadCloud(file);
  Cloud::Ptr cloud(new Cloud);
  std::copy_if(loaded->begin(), loaded->end(), std::back_inserter(*cloud),
               [](const pcl::PointXYZ& p) { return pcl::isFinite(p); });
  if (cloud->empty()) throw ToolError(kExitInput, "'" + file + "' has no finite points to register");
  if (cloud->size() < loaded->size())
    print_warn("'%s': %zu of %zu points dropped (NaN/Inf)\n", file.c_str(), loaded->size() - cloud->size(),
               loaded->size());
  if (leaf > 0) {
    Cloud::Ptr filtered(new Cloud);
    pcl::VoxelGrid<pcl::PointXYZ> grid;
    grid.setInputCloud(cloud);
    grid.setLeafSize(leaf, leaf, leaf);
    grid.filter(*filtered);
    cloud = filtered;
  }
  return cloud;
}

}  // namespace

int main(int argc, char** argv) {
  return runTool("fot_icp_psi", "fot_icp_psi source.pcd|.ply target.pcd|.ply [options]", [&] {
    const Arguments args(argc, argv, {"-guess", "-leaf", "-res", "-max_range", "-max_corr", "-iterations"},
                         {"-h", "--help"}, 2, 2);
    if (args.helpAsked()) {
      printHelp("fot_icp_psi");
      return kExitOk;
    }
    std::vector<double> guess{0, 0, 0, 0};
    args.get("-guess", guess, 4, true);
    float leaf = 0.1f;
    double res = 0.1, max_range = 1.0, max_corr = 0.5;
    int iterations = 50;
    if (args.get("-leaf", leaf) && leaf < 0) throw ToolError(kExitUsage, "option -leaf must not be negative");
    args.getResolution(res);
    args.getPositive("-max_range", max_range);
    args.getPositive("-max_corr", max_corr);
    if (args.get("-iterations", iterations) && iterations < 1)
      throw ToolError(kExitUsage, "option -iterations must be at least 1");
    const Cloud::Ptr source = registrationInput(args.positional()[0], leaf),
                     target = registrationInput(args.positional()[1], leaf);
    const Eigen::Matrix4f initial = (Eigen::Translation3f(guess[0], guess[1], guess[2]) *
                                     Eigen::AngleAxisf(guess[3], Eigen::Vector3f::UnitZ()))
                                        .matrix();
    pcl::IterativeClosestPoint<pcl::PointXYZ, pcl::PointXYZ> icp;
    icp.setInputSource(source);
    icp.setInputTarget(target);
    icp.setMaximumIterations(iterations);
    icp.setMaxCorrespondenceDistance(max_corr);

    const pcl::fot::registration::TransformationValidationPsi<pcl::PointXYZ, pcl::PointXYZ> validation(
        res, max_range);
    print_info("%zu source and %zu target points; psi at %g m cells, capped at %g m\n", source->size(),
               target->size(), res, max_range);
    print_info("%-12s %12s %18s %16s\n", "", "psi [m]", "getFitnessScore", "corr. MSE");
    print_info("%-12s %12.5f\n", "guess", validation.validateTransformation(source, target, initial));

    // ICP hands the rejector each iteration's pose before the step: ψ and ICP's fitness there.
    auto rejector =
        pcl::make_shared<pcl::fot::registration::CorrespondenceRejectorPsi<pcl::PointXYZ>>(res, max_range);
    rejector->setCallback([&](std::size_t iteration, double psi, double mse) {
      print_info("iteration %-2zu %12.5f %18.6f %16.6f\n", iteration + 1, psi, icp.getFitnessScore(), mse);
    });
    icp.addCorrespondenceRejector(rejector);

    TicToc timer;
    timer.tic();
    Cloud aligned;
    icp.align(aligned, initial);
    const double ms = timer.toc();
    const Eigen::Matrix4f final_pose = icp.getFinalTransformation();
    print_info("%-12s %12.5f %18.6f\n", icp.hasConverged() ? "converged" : "stopped",
               validation.validateTransformation(source, target, final_pose), icp.getFitnessScore());
    print_info("ICP %s after %zu iterations in %.0f ms; final transformation:\n",
               icp.hasConverged() ? "converged" : "did not converge", rejector->history().size(), ms);
    for (int r = 0; r < 4; ++r)
      print_info("  %10.6f %10.6f %10.6f %10.6f\n", final_pose(r, 0), final_pose(r, 1), final_pose(r, 2),
                 final_pose(r, 3));
    return icp.hasConverged() ? kExitOk : kExitNotConverged;
  });
}
