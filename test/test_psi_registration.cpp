// ψ as a registration score: TransformationValidationPsi and the ICP hooks.
#include <gtest/gtest.h>

#include <cfloat>

#include <pcl/common/transforms.h>
#include <pcl/filters/voxel_grid.h>
#include <pcl/registration/icp.h>

#include <pcl_fot/pcl/registration/correspondence_rejection_psi.h>
#include <pcl_fot/pcl/registration/transformation_validation_psi.h>

#include "scan_data.h"

using pcl::PointXYZ;
using Cloud = pcl::PointCloud<PointXYZ>;
using Validation = pcl::fot::registration::TransformationValidationPsi<PointXYZ, PointXYZ>;

namespace {

Cloud::Ptr downsampled(const std::string& name, float leaf) {
  Cloud::Ptr out(new Cloud);
  pcl::VoxelGrid<PointXYZ> grid;
  grid.setInputCloud(pcl_fot_test::loadScan(name));
  grid.setLeafSize(leaf, leaf, leaf);
  grid.filter(*out);
  return out;
}

/** The NDT tutorial's initial guess for room_scan2 onto room_scan1 (see the data README). */
Eigen::Matrix4f tutorialGuess() {
  return (Eigen::Translation3f(1.79387f, 0.720047f, 0.0f) *
          Eigen::AngleAxisf(0.6931f, Eigen::Vector3f::UnitZ()))
      .matrix();
}

}  // namespace

PCL_FOT_SCAN_TESTS(TransformationValidationPsiOnScans);

TEST_P(TransformationValidationPsiOnScans, RanksACorrectRegistrationAboveWrongOnes) {
  const Cloud::Ptr target = downsampled("room_scan1.pcd", 0.1f), source = downsampled("room_scan2.pcd", 0.1f);
  pcl::IterativeClosestPoint<PointXYZ, PointXYZ> icp;
  icp.setInputSource(source);
  icp.setInputTarget(target);
  icp.setMaximumIterations(60);
  icp.setMaxCorrespondenceDistance(0.5);
  Cloud aligned;
  icp.align(aligned, tutorialGuess());
  ASSERT_TRUE(icp.hasConverged());
  const Eigen::Matrix4f refined = icp.getFinalTransformation();

  const Validation psi(0.1, 1.0);
  const double s_refined = psi.validateTransformation(source, target, refined);
  const double s_guess = psi.validateTransformation(source, target, tutorialGuess());
  const double s_identity = psi.validateTransformation(source, target, Eigen::Matrix4f::Identity());
  Eigen::Matrix4f off = refined;
  off(0, 3) += 0.5f;
  const double s_off = psi.validateTransformation(source, target, off);
  EXPECT_LT(s_refined, s_guess) << "ICP's refinement scores better than its starting guess";
  EXPECT_LT(s_guess, s_identity);
  EXPECT_LT(s_refined, s_off) << "half a metre off scores worse";
  EXPECT_TRUE(psi(s_refined, s_identity)) << "operator(): lower is better";
  EXPECT_FALSE(psi(s_identity, s_refined));

  Validation gate(0.1, 1.0);
  EXPECT_FALSE(gate.isValid(source, target, refined)) << "no threshold set yet";
  gate.setThreshold(0.5 * (s_refined + s_off));
  EXPECT_TRUE(gate.isValid(source, target, refined));
  EXPECT_FALSE(gate.isValid(source, target, off));
}

TEST_P(TransformationValidationPsiOnScans, AKnownTransformScoresNearZero) {
  const Cloud::Ptr target = downsampled("room_scan1.pcd", 0.05f);
  const Eigen::Affine3f truth =
      Eigen::Translation3f(0.4f, -0.3f, 0.1f) * Eigen::AngleAxisf(0.2f, Eigen::Vector3f::UnitZ());
  Cloud::Ptr source(new Cloud);
  pcl::transformPointCloud(*target, *source, truth.inverse());
  // Through the base class, as an algorithm that takes any TransformationValidation would hold it.
  const pcl::registration::TransformationValidation<PointXYZ, PointXYZ>::Ptr v(new Validation(0.1, 1.0));
  const double right = v->validateTransformation(source, target, truth.matrix());
  const double wrong = v->validateTransformation(source, target, Eigen::Matrix4f::Identity());
  EXPECT_LT(right, 0.1) << "re-voxelising moved points costs at most about a cell";
  EXPECT_GT(wrong, 5 * right);
}

TEST_P(TransformationValidationPsiOnScans, TheTargetTreeFollowsItsCloud) {
  Cloud::Ptr target = downsampled("room_scan2.pcd", 0.1f);
  const Cloud::Ptr source(new Cloud(*target));
  const Validation psi(0.1, 1.0);
  const Eigen::Matrix4f identity = Eigen::Matrix4f::Identity();
  EXPECT_DOUBLE_EQ(psi.validateTransformation(source, target, identity), 0.0);
  for (auto& p : *target) p.x += 0.3f;  // the same cloud object, changed in place
  EXPECT_GT(psi.validateTransformation(source, target, identity), 0.1) << "the cached tree is rebuilt";
}

TEST(TransformationValidationPsi, BadInput) {
  EXPECT_THROW(Validation(0.0), std::invalid_argument);
  EXPECT_THROW(Validation(-0.1), std::invalid_argument);
  const Validation psi(0.1);
  Cloud::Ptr empty(new Cloud), one(new Cloud);
  one->push_back(PointXYZ(1, 2, 3));
  EXPECT_EQ(psi.validateTransformation(empty, one, Eigen::Matrix4f::Identity()), DBL_MAX);
  EXPECT_EQ(psi.validateTransformation(one, empty, Eigen::Matrix4f::Identity()), DBL_MAX);
  Cloud::Ptr nans(new Cloud);
  nans->push_back(PointXYZ(std::nanf(""), 0, 0));
  EXPECT_EQ(psi.validateTransformation(nans, one, Eigen::Matrix4f::Identity()), DBL_MAX);
  // Caps too large for any distance, or not numbers, cap nothing.
  Cloud::Ptr far(new Cloud);
  far->push_back(PointXYZ(41, 2, 3));
  const double uncapped = Validation(0.1, 0.0).validateTransformation(far, one, Eigen::Matrix4f::Identity());
  EXPECT_GT(uncapped, 0.0);
  for (double range : {1e300, double(INFINITY), double(NAN)})
    EXPECT_EQ(Validation(0.1, range).validateTransformation(far, one, Eigen::Matrix4f::Identity()), uncapped)
        << range;
  EXPECT_LT(Validation(0.1, 1.0).validateTransformation(far, one, Eigen::Matrix4f::Identity()), uncapped);
}

PCL_FOT_SCAN_TESTS(PsiInIcp);

TEST_P(PsiInIcp, TheRejectorScoresEveryIterationAndTheCriteriaCanStop) {
  const Cloud::Ptr target = downsampled("room_scan1.pcd", 0.1f), source = downsampled("room_scan2.pcd", 0.1f);
  auto run = [&](bool stop_on_psi, std::vector<double>& history, std::vector<double>& mse) {
    pcl::IterativeClosestPoint<PointXYZ, PointXYZ> icp;
    icp.setInputSource(source);
    icp.setInputTarget(target);
    icp.setMaximumIterations(40);
    icp.setTransformationEpsilon(1e-12);
    icp.setEuclideanFitnessEpsilon(0);
    icp.setMaxCorrespondenceDistance(0.5);
    auto rejector = pcl::make_shared<pcl::fot::registration::CorrespondenceRejectorPsi<PointXYZ>>(0.1, 1.0);
    rejector->setCallback([&](std::size_t, double, double m) { mse.push_back(m); });
    icp.addCorrespondenceRejector(rejector);
    if (stop_on_psi) {
      auto criteria = pcl::make_shared<pcl::fot::registration::PsiConvergenceCriteria<float>>(
          *icp.getConvergeCriteria(), rejector->history());
      criteria->setRelativePsiImprovement(0.01);
      icp.convergence_criteria_ = criteria;
    }
    Cloud aligned;
    icp.align(aligned, tutorialGuess());
    history = rejector->history();
    return icp.getFitnessScore();
  };
  std::vector<double> full, full_mse, early, early_mse;
  run(false, full, full_mse);
  run(true, early, early_mse);
  ASSERT_GE(full.size(), 3u);
  EXPECT_EQ(full.size(), full_mse.size()) << "one score per iteration";
  EXPECT_LT(full.back(), full.front()) << "ICP improves ψ";
  EXPECT_LT(full_mse.back(), full_mse.front());
  EXPECT_LT(early.size(), full.size()) << "ψ's convergence test stops ICP sooner";
  EXPECT_EQ(std::vector<double>(full.begin(), full.begin() + early.size()), early)
      << "the same steps until then";
}
