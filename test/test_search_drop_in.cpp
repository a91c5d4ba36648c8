// FastOctTreeSearch inside PCL's algorithms: ICP, NormalEstimation, EuclideanClusterExtraction.
#include <gtest/gtest.h>

#include <pcl/common/point_tests.h>
#include <pcl/common/transforms.h>
#include <pcl/features/normal_3d.h>
#include <pcl/filters/voxel_grid.h>
#include <pcl/registration/icp.h>
#include <pcl/segmentation/extract_clusters.h>

#include <pcl_fot/search/fast_oct_tree_search.h>

#include "scan_data.h"

using pcl::PointXYZ;
using Cloud = pcl::PointCloud<PointXYZ>;
using Search = pcl::fot::search::FastOctTreeSearch<PointXYZ>;

namespace {

struct Registration {
  bool converged;
  Eigen::Matrix4f transformation;
  double fitness;
};

/** ICP of source onto target with our search on the target, `cell` metres. */
Registration registerWithOurSearch(const Cloud::Ptr& source, const Cloud::Ptr& target, double cell,
                                   double max_correspondence_distance) {
  pcl::IterativeClosestPoint<PointXYZ, PointXYZ> icp;
  icp.setSearchMethodTarget(Search::Ptr(new Search(cell)));
  icp.setInputSource(source);
  icp.setInputTarget(target);
  icp.setMaximumIterations(100);
  icp.setTransformationEpsilon(1e-10);
  icp.setMaxCorrespondenceDistance(max_correspondence_distance);
  Cloud aligned;
  icp.align(aligned);
  return {icp.hasConverged(), icp.getFinalTransformation(), icp.getFitnessScore()};
}

}  // namespace

TEST(SearchDropIn, IcpRecoversAKnownTransform) {
  Cloud::Ptr target(new Cloud), source(new Cloud);
  pcl::VoxelGrid<PointXYZ> grid;
  grid.setInputCloud(pcl_fot_test::loadScan("room_scan1.pcd"));
  grid.setLeafSize(0.1f, 0.1f, 0.1f);
  grid.filter(*target);
  const Eigen::Affine3f truth =
      Eigen::Translation3f(0.25f, -0.15f, 0.05f) * Eigen::AngleAxisf(0.06f, Eigen::Vector3f::UnitZ());
  pcl::transformPointCloud(*target, *source, truth.inverse());

  const Registration r = registerWithOurSearch(source, target, 0.1, 1.0);
  ASSERT_TRUE(r.converged);
  const Eigen::Matrix4f error = r.transformation * truth.inverse().matrix();
  EXPECT_LT((error.block<3, 1>(0, 3)).norm(), 0.01) << "translation recovered within 1 cm";
  EXPECT_LT(Eigen::AngleAxisf(Eigen::Matrix3f(error.block<3, 3>(0, 0))).angle(), 0.002)
      << "rotation within 0.1°";
  EXPECT_LT(r.fitness, 1e-4);
}

/**
 * An organised Kinect frame, its NaN points kept, registered onto its moved finite points. KdTreeFLANN
 * asserts on a NaN query; PCL's correspondence estimation reads our placeholder at an infinite distance
 * and passes over the point, so ICP works on the finite points alone.
 */
TEST(SearchDropIn, IcpPassesOverTheNanPointsOfAnOrganisedSource) {
  const Cloud::Ptr frame = pcl_fot_test::loadScan("kinect_capture0001.pcd");
  Cloud::Ptr organised(new Cloud(frame->width / 4, frame->height / 4)), finite(new Cloud), target(new Cloud);
  for (std::uint32_t r = 0; r < organised->height; ++r)
    for (std::uint32_t c = 0; c < organised->width; ++c) (*organised)(c, r) = (*frame)(4 * c, 4 * r);
  organised->is_dense = false;
  for (const PointXYZ& p : *organised)
    if (pcl::isFinite(p)) finite->push_back(p);
  ASSERT_GT(organised->size() - finite->size(), 1000u) << "the frame has NaN points";
  const Eigen::Affine3f truth =
      Eigen::Translation3f(0.03f, -0.02f, 0.01f) * Eigen::AngleAxisf(0.02f, Eigen::Vector3f::UnitY());
  pcl::transformPointCloud(*finite, *target, truth);

  const Registration with_nan = registerWithOurSearch(organised, target, 0.02, 0.2);
  const Registration without = registerWithOurSearch(finite, target, 0.02, 0.2);
  ASSERT_TRUE(with_nan.converged && without.converged);
  ASSERT_TRUE(with_nan.transformation.allFinite());
  EXPECT_TRUE(with_nan.transformation.isApprox(without.transformation, 1e-6f))
      << with_nan.transformation << "\nagainst\n"
      << without.transformation;
  EXPECT_LT((with_nan.transformation.block<3, 1>(0, 3) - truth.translation()).norm(), 0.005);
  EXPECT_TRUE(std::isfinite(with_nan.fitness));
  EXPECT_NEAR(with_nan.fitness, without.fitness, 1e-9);
}

/**
 * The same neighbours give the same normals. Two things are ambiguous by nature and left out: a point whose
 * k-th and (k+1)-th neighbours lie at exactly the same distance (FLANN and we may each keep either), and for
 * radius searches a neighbour exactly on the sphere (KdTreeFLANN keeps d < float(r²), ours d <= r², as
 * BruteForce). Neighbours at
 * equal distance also come in FLANN's traversal order there and by index here, and the covariance sums them
 * in that order, so the normals agree to float rounding, not always to the last bit.
 */
TEST(SearchDropIn, NormalEstimationGivesTheSameNormals) {
  const Cloud::Ptr cloud = pcl_fot_test::loadScan("kinect_capture0001.pcd");
  pcl::search::KdTree<PointXYZ>::Ptr kdtree(new pcl::search::KdTree<PointXYZ>);
  Search::Ptr ours(new Search(0.01));
  kdtree->setInputCloud(cloud);
  ours->setInputCloud(cloud);
  constexpr int k = 12;
  constexpr double radius = 0.03;
  std::vector<bool> ambiguous_k(cloud->size(), false), ambiguous_r(cloud->size(), false);
  pcl::Indices a, b;
  std::vector<float> da, db;
  for (std::size_t i = 0; i < cloud->size(); ++i) {
    if (!pcl::isFinite((*cloud)[i])) continue;
    kdtree->nearestKSearch((*cloud)[i], k, a, da);
    ours->nearestKSearch((*cloud)[i], k + 1, b, db);
    ASSERT_EQ(da, std::vector<float>(db.begin(), db.begin() + k))
        << "the same neighbour distances, point " << i;
    ambiguous_k[i] = db.size() > std::size_t(k) && db[k - 1] == db[k];
    ours->radiusSearch((*cloud)[i], radius, b, db);
    // KdTreeFLANN keeps d < float(r²); BruteForce and we keep d <= r² in double.
    ambiguous_r[i] = !db.empty() && db.back() >= float(radius * radius);
  }

  for (bool by_radius : {false, true}) {
    pcl::NormalEstimation<PointXYZ, pcl::Normal> ne;
    ne.setInputCloud(cloud);
    if (by_radius)
      ne.setRadiusSearch(radius);
    else
      ne.setKSearch(k);
    pcl::PointCloud<pcl::Normal> with_kdtree, with_fot;
    ne.setSearchMethod(kdtree);
    ne.compute(with_kdtree);
    ne.setSearchMethod(ours);
    ne.compute(with_fot);
    ASSERT_EQ(with_kdtree.size(), with_fot.size());
    std::size_t compared = 0, skipped = 0;
    for (std::size_t i = 0; i < with_fot.size(); ++i) {
      const auto& x = with_kdtree[i];
      const auto& y = with_fot[i];
      if ((by_radius ? ambiguous_r : ambiguous_k)[i]) {
        ++skipped;
        continue;
      }
      ASSERT_EQ(std::isfinite(x.normal_x), std::isfinite(y.normal_x)) << "point " << i;
      if (!std::isfinite(x.normal_x)) continue;
      ASSERT_NEAR(x.normal_x, y.normal_x, 1e-4) << "point " << i;
      ASSERT_NEAR(x.normal_y, y.normal_y, 1e-4) << "point " << i;
      ASSERT_NEAR(x.normal_z, y.normal_z, 1e-4) << "point " << i;
      ASSERT_NEAR(x.curvature, y.curvature, 1e-4) << "point " << i;
      ++compared;
    }
    EXPECT_GT(compared, 200000u);
    EXPECT_LT(skipped, compared / 4) << "ambiguous neighbourhoods are the exception";
  }
}

TEST(SearchDropIn, EuclideanClustersAreTheSame) {
  Cloud::Ptr cloud(new Cloud);
  pcl::VoxelGrid<PointXYZ> grid;
  grid.setInputCloud(pcl_fot_test::loadScan("room_scan2.pcd"));
  grid.setLeafSize(0.05f, 0.05f, 0.05f);
  grid.filter(*cloud);
  auto clusters = [&](const pcl::search::Search<PointXYZ>::Ptr& search) {
    pcl::EuclideanClusterExtraction<PointXYZ> ec;
    ec.setClusterTolerance(0.12);
    ec.setMinClusterSize(20);
    ec.setMaxClusterSize(1000000);
    ec.setSearchMethod(search);
    ec.setInputCloud(cloud);
    std::vector<pcl::PointIndices> out;
    ec.extract(out);
    std::vector<pcl::Indices> sets;
    for (auto& c : out) {
      std::sort(c.indices.begin(), c.indices.end());
      sets.push_back(c.indices);
    }
    std::sort(sets.begin(), sets.end());
    return sets;
  };
  const auto expected = clusters(pcl::search::KdTree<PointXYZ>::Ptr(new pcl::search::KdTree<PointXYZ>));
  const auto got = clusters(Search::Ptr(new Search(0.05)));
  EXPECT_GT(expected.size(), 3u);
  EXPECT_EQ(expected, got);
}
