#pragma once

#include <cstdint>
#include <limits>
#include <memory>
#include <mutex>

#include <pcl/registration/transformation_validation.h>

#include <pcl_fot/psi/psi.h>
#include <pcl_fot/tree/fast_oct_tree.h>

namespace pcl {
namespace fot {
namespace registration {

/**
 * Scores a registration with the map similarity ψ of Poppinga et al. (see pcl_fot/psi/psi.h), as a PCL
 * TransformationValidation: rank hypotheses with operator() (lower is better) or accept one with isValid().
 *
 * validateTransformation() voxelises the source moved by the transformation and compares it with the
 * target's voxels: the mean Manhattan distance per occupied cell, in metres, each cell's distance counting
 * at most max_range (a robust score: a few far outliers do not dominate it). The target's tree is built
 * once and kept while the target stays the same cloud (same pointer, size and coordinates).
 * PCL's TransformationValidation is consumed by no PCL algorithm; to score inside an ICP loop, see
 * CorrespondenceRejectorPsi and PsiConvergenceCriteria.
 */
template <typename PointSource, typename PointTarget, typename Scalar = float>
class TransformationValidationPsi
    : public pcl::registration::TransformationValidation<PointSource, PointTarget, Scalar> {
 public:
  using Base = pcl::registration::TransformationValidation<PointSource, PointTarget, Scalar>;
  using Ptr = shared_ptr<TransformationValidationPsi<PointSource, PointTarget, Scalar>>;
  using ConstPtr = shared_ptr<const TransformationValidationPsi<PointSource, PointTarget, Scalar>>;
  using typename Base::Matrix4;
  using typename Base::PointCloudSourceConstPtr;
  using typename Base::PointCloudTargetConstPtr;

  /**
   * `resolution`: the cell edge in metres; `max_range`: the most one cell's distance counts (≤ 0, NaN or
   * Inf: no cap).
   */
  explicit TransformationValidationPsi(double resolution = 0.05, double max_range = 1.0);

  void setResolution(double resolution);
  double getResolution() const { return resolution_; }
  void setMaxRange(double max_range) { max_range_ = max_range; }
  double getMaxRange() const { return max_range_; }
  /** isValid() accepts scores below it; unset (NaN) until given, as in PCL's Euclidean validation. */
  void setThreshold(double threshold) { threshold_ = threshold; }
  double getThreshold() const { return threshold_; }

  /** The mean ψ distance per cell in metres; DBL_MAX when either cloud has no finite point. */
  double validateTransformation(const PointCloudSourceConstPtr& cloud_src,
                                const PointCloudTargetConstPtr& cloud_tgt,
                                const Matrix4& transformation_matrix) const override;
  /** The whole ψ result behind validateTransformation(); undefined when either cloud has no finite point. */
  pcl::fot::PsiResult score(const PointCloudSourceConstPtr& cloud_src,
                            const PointCloudTargetConstPtr& cloud_tgt,
                            const Matrix4& transformation_matrix) const;

  /** True if score1 is better (lower) than score2. */
  bool operator()(const double& score1, const double& score2) const override { return score1 < score2; }
  bool isValid(const PointCloudSourceConstPtr& cloud_src, const PointCloudTargetConstPtr& cloud_tgt,
               const Matrix4& transformation_matrix) const override;

  PCL_MAKE_ALIGNED_OPERATOR_NEW

 private:
  /** The target's tree, built on first use and whenever the target changes. */
  std::shared_ptr<const pcl::fot::FastOctTree> targetTree(const PointCloudTargetConstPtr& cloud_tgt) const;

  double resolution_;
  double max_range_;
  double threshold_ = std::numeric_limits<double>::quiet_NaN();
  mutable std::mutex cache_mutex_;
  mutable const void* cached_cloud_ = nullptr;
  mutable std::uint64_t cached_fingerprint_ = 0;
  mutable std::shared_ptr<const pcl::fot::FastOctTree> cached_tree_;
};

}  // namespace registration
}  // namespace fot
}  // namespace pcl

// Header-only, as PCL's registration classes are: any source and target point types, float or double.
#include <pcl_fot/pcl/registration/impl/transformation_validation_psi.hpp>
