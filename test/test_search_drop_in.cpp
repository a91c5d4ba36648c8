// FastOctTreeSearch inside PCL's algorithms: ICP, GICP, correspondence estimation, NormalEstimation (and its
// OpenMP form), FPFH, MovingLeastSquares, greedy triangulation, ISS keypoints, region growing and
// EuclideanClusterExtraction.
#include <gtest/gtest.h>

#include <array>

#include <pcl/common/point_tests.h>
#include <pcl/common/transforms.h>
#include <pcl/features/fpfh.h>
#include <pcl/features/normal_3d.h>
#include <pcl/features/normal_3d_omp.h>
#include <pcl/filters/voxel_grid.h>
#include <pcl/keypoints/iss_3d.h>
#include <pcl/registration/correspondence_estimation.h>
#include <pcl/registration/gicp.h>
#include <pcl/registration/icp.h>
#include <pcl/segmentation/extract_clusters.h>
#include <pcl/segmentation/region_growing.h>
#include <pcl/surface/gp3.h>
#include <pcl/surface/mls.h>

#include <pcl_fot/pcl/search/fast_oct_tree_search.h>

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

PCL_FOT_SCAN_TESTS(SearchDropIn);

TEST_P(SearchDropIn, IcpRecoversAKnownTransform) {
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
TEST_P(SearchDropIn, IcpPassesOverTheNanPointsOfAnOrganisedSource) {
  const Cloud::Ptr frame = pcl_fot_test::loadScan("kinect_capture0001.pcd");
  Cloud::Ptr organised(new Cloud(frame->width / 4, frame->height / 4)), finite(new Cloud), target(new Cloud);
  for (std::uint32_t r = 0; r < organised->height; ++r)
    for (std::uint32_t c = 0; c < organised->width; ++c) (*organised)(c, r) = (*frame)(4 * c, 4 * r);
  organised->is_dense = false;
  for (const PointXYZ& p : *organised)
    if (pcl::isFinite(p)) finite->push_back(p);
  ASSERT_GT(organised->size() - finite->size(), organised->size() / 20) << "the frame has NaN points";
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
TEST_P(SearchDropIn, NormalEstimationGivesTheSameNormals) {
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

    // OpenMP threads share one search, as NormalEstimationOMP runs it: the same normals to the bit.
    pcl::NormalEstimationOMP<PointXYZ, pcl::Normal> threaded(4);
    threaded.setInputCloud(cloud);
    if (by_radius)
      threaded.setRadiusSearch(radius);
    else
      threaded.setKSearch(k);
    threaded.setSearchMethod(ours);
    pcl::PointCloud<pcl::Normal> with_fot_threads;
    threaded.compute(with_fot_threads);
    ASSERT_EQ(with_fot_threads.size(), with_fot.size());
    for (std::size_t i = 0; i < with_fot.size(); ++i) {
      const auto& x = with_fot[i];
      const auto& y = with_fot_threads[i];
      const std::array<float, 4> a{x.normal_x, x.normal_y, x.normal_z, x.curvature},
          b{y.normal_x, y.normal_y, y.normal_z, y.curvature};
      for (int c = 0; c < 4; ++c)
        ASSERT_TRUE(a[c] == b[c] || (std::isnan(a[c]) && std::isnan(b[c]))) << "threaded, point " << i;
    }
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
    EXPECT_GT(compared, with_fot.size() / 2);
    EXPECT_LT(skipped, compared / 4) << "ambiguous neighbourhoods are the exception";
  }
}

TEST_P(SearchDropIn, EuclideanClustersAreTheSame) {
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

/**
 * Each algorithm run twice on a room scan, once with KdTree and once with ours, as setSearchMethod takes
 * them: the results agree to float rounding (neighbours at equal distance may come in another order).
 */
TEST_P(SearchDropIn, FeaturesSurfacesKeypointsSegmentationAndGicpAsWithKdTree) {
  Cloud::Ptr cloud(new Cloud), moved(new Cloud);
  pcl::VoxelGrid<PointXYZ> grid;
  grid.setInputCloud(pcl_fot_test::loadScan("room_scan1.pcd"));
  grid.setLeafSize(0.08f, 0.08f, 0.08f);
  grid.filter(*cloud);
  pcl::PointCloud<pcl::Normal>::Ptr normals(new pcl::PointCloud<pcl::Normal>);
  pcl::NormalEstimation<PointXYZ, pcl::Normal> ne;
  ne.setInputCloud(cloud);
  ne.setRadiusSearch(0.25);
  ne.compute(*normals);
  using KdTree = pcl::search::KdTree<PointXYZ>;
  const auto make = [](bool ours) { return ours ? KdTree::Ptr(new Search) : KdTree::Ptr(new KdTree); };

  std::array<pcl::PointCloud<pcl::FPFHSignature33>, 2> fpfh;
  std::array<pcl::PointCloud<pcl::PointNormal>, 2> mls;
  std::array<std::vector<pcl::PointIndices>, 2> regions;
  std::array<pcl::Correspondences, 2> reciprocal;
  std::array<Eigen::Matrix4f, 2> gicp;
  std::array<pcl::PolygonMesh, 2> meshes;
  std::array<Cloud, 2> keypoints;
  pcl::PointCloud<pcl::PointNormal>::Ptr with_normals(new pcl::PointCloud<pcl::PointNormal>);
  pcl::concatenateFields(*cloud, *normals, *with_normals);
  using NormalSearch = pcl::search::KdTree<pcl::PointNormal>;
  const Eigen::Affine3f truth =
      Eigen::Translation3f(0.2f, -0.1f, 0.03f) * Eigen::AngleAxisf(0.05f, Eigen::Vector3f::UnitZ());
  pcl::transformPointCloud(*cloud, *moved, truth.inverse());
  for (const bool ours : {false, true}) {
    pcl::FPFHEstimation<PointXYZ, pcl::Normal, pcl::FPFHSignature33> f;
    f.setInputCloud(cloud);
    f.setInputNormals(normals);
    f.setSearchMethod(make(ours));
    f.setRadiusSearch(0.4);
    f.compute(fpfh[ours]);

    pcl::MovingLeastSquares<PointXYZ, pcl::PointNormal> m;
    m.setInputCloud(cloud);
    m.setSearchMethod(make(ours));
    m.setSearchRadius(0.25);
    m.setComputeNormals(true);
    m.process(mls[ours]);

    pcl::GreedyProjectionTriangulation<pcl::PointNormal> gp3;
    gp3.setInputCloud(with_normals);
    gp3.setSearchMethod(ours ? NormalSearch::Ptr(new pcl::fot::search::FastOctTreeSearch<pcl::PointNormal>)
                             : NormalSearch::Ptr(new NormalSearch));
    gp3.setSearchRadius(0.4);
    gp3.setMu(2.5);
    gp3.setMaximumNearestNeighbors(100);
    gp3.reconstruct(meshes[ours]);

    pcl::ISSKeypoint3D<PointXYZ, PointXYZ> iss;
    iss.setInputCloud(cloud);
    iss.setSearchMethod(make(ours));
    iss.setSalientRadius(0.48);
    iss.setNonMaxRadius(0.32);
    iss.setMinNeighbors(5);
    iss.setNumberOfThreads(2);
    iss.compute(keypoints[ours]);

    pcl::RegionGrowing<PointXYZ, pcl::Normal> rg;
    rg.setInputCloud(cloud);
    rg.setInputNormals(normals);
    rg.setSearchMethod(make(ours));
    rg.setNumberOfNeighbours(30);
    rg.setMinClusterSize(30);
    rg.extract(regions[ours]);

    pcl::registration::CorrespondenceEstimation<PointXYZ, PointXYZ> ce;
    ce.setInputSource(moved);
    ce.setInputTarget(cloud);
    ce.setSearchMethodSource(make(ours));
    ce.setSearchMethodTarget(make(ours));
    ce.determineReciprocalCorrespondences(reciprocal[ours], 0.3);

    pcl::GeneralizedIterativeClosestPoint<PointXYZ, PointXYZ> g;
    g.setSearchMethodSource(make(ours));
    g.setSearchMethodTarget(make(ours));
    g.setInputSource(moved);
    g.setInputTarget(cloud);
    g.setMaxCorrespondenceDistance(0.5);
    Cloud aligned;
    g.align(aligned);
    ASSERT_TRUE(g.hasConverged());
    gicp[ours] = g.getFinalTransformation();
  }

  ASSERT_EQ(fpfh[0].size(), cloud->size());
  ASSERT_EQ(fpfh[1].size(), cloud->size());
  for (std::size_t i = 0; i < cloud->size(); ++i)
    for (int b = 0; b < 33; ++b)
      ASSERT_NEAR(fpfh[0][i].histogram[b], fpfh[1][i].histogram[b], 1e-3) << "FPFH of point " << i;
  ASSERT_GT(mls[0].size(), cloud->size() / 2);
  ASSERT_EQ(mls[0].size(), mls[1].size());
  for (std::size_t i = 0; i < mls[0].size(); ++i) {  // not the normals: PCL 1.13 leaves some uninitialised
    ASSERT_NEAR(mls[0][i].x, mls[1][i].x, 1e-5) << "MLS point " << i;
    ASSERT_NEAR(mls[0][i].y, mls[1][i].y, 1e-5) << "MLS point " << i;
    ASSERT_NEAR(mls[0][i].z, mls[1][i].z, 1e-5) << "MLS point " << i;
  }
  ASSERT_GT(meshes[0].polygons.size(), cloud->size() / 2);
  ASSERT_EQ(meshes[0].polygons.size(), meshes[1].polygons.size());
  for (std::size_t i = 0; i < meshes[0].polygons.size(); ++i)
    ASSERT_EQ(meshes[0].polygons[i].vertices, meshes[1].polygons[i].vertices) << "triangle " << i;
  ASSERT_GT(keypoints[0].size(), 10u);
  ASSERT_EQ(keypoints[0].size(), keypoints[1].size());
  for (std::size_t i = 0; i < keypoints[0].size(); ++i)
    ASSERT_EQ(keypoints[0][i].getVector3fMap(), keypoints[1][i].getVector3fMap()) << "ISS keypoint " << i;
  ASSERT_GT(regions[0].size(), 3u);
  ASSERT_EQ(regions[0].size(), regions[1].size());
  for (std::size_t r = 0; r < regions[0].size(); ++r) EXPECT_EQ(regions[0][r].indices, regions[1][r].indices);
  ASSERT_GT(reciprocal[0].size(), cloud->size() / 4);
  ASSERT_EQ(reciprocal[0].size(), reciprocal[1].size());
  for (std::size_t i = 0; i < reciprocal[0].size(); ++i) {
    ASSERT_EQ(reciprocal[0][i].index_query, reciprocal[1][i].index_query);
    ASSERT_EQ(reciprocal[0][i].index_match, reciprocal[1][i].index_match);
    ASSERT_EQ(reciprocal[0][i].distance, reciprocal[1][i].distance);
  }
  EXPECT_TRUE(gicp[1].isApprox(gicp[0], 1e-5f)) << gicp[1] << "\nagainst\n" << gicp[0];
  const Eigen::Matrix4f error = gicp[1] * truth.inverse().matrix();
  EXPECT_LT((error.block<3, 1>(0, 3)).norm(), 1e-3);
}
