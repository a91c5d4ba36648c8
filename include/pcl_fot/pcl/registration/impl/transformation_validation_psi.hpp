#pragma once

#include <cfloat>
#include <cmath>
#include <stdexcept>

#include <pcl/common/transforms.h>
#include <pcl/console/print.h>

#include <pcl_fot/detail/cloud_fingerprint.h>
#include <pcl_fot/pcl/cloud_insertion.h>
#include <pcl_fot/pcl/registration/transformation_validation_psi.h>

namespace pcl {
namespace fot {
namespace registration {

template <typename PointSource, typename PointTarget, typename Scalar>
TransformationValidationPsi<PointSource, PointTarget, Scalar>::TransformationValidationPsi(double resolution,
                                                                                           double max_range)
    : resolution_(resolution), max_range_(max_range) {
  pcl::fot::CellGrid check(resolution);  // throws for a resolution CellGrid refuses
  (void)check;
}

template <typename PointSource, typename PointTarget, typename Scalar>
void TransformationValidationPsi<PointSource, PointTarget, Scalar>::setResolution(double resolution) {
  pcl::fot::CellGrid check(resolution);
  (void)check;
  std::lock_guard<std::mutex> lock(cache_mutex_);
  resolution_ = resolution;
  cached_tree_.reset();
}

template <typename PointSource, typename PointTarget, typename Scalar>
std::shared_ptr<const pcl::fot::FastOctTree>
TransformationValidationPsi<PointSource, PointTarget, Scalar>::targetTree(
    const PointCloudTargetConstPtr& cloud_tgt) const {
  const std::uint64_t fingerprint =
      cloud_tgt->empty()
          ? 0
          : pcl::fot::detail::cloudFingerprint(&(*cloud_tgt)[0].x, cloud_tgt->size(), sizeof(PointTarget));
  std::lock_guard<std::mutex> lock(cache_mutex_);
  if (!cached_tree_ || cached_cloud_ != cloud_tgt.get() || cached_fingerprint_ != fingerprint) {
    auto tree = std::make_shared<pcl::fot::FastOctTree>(resolution_);
    pcl::fot::insertPointCloud(*tree, *cloud_tgt);
    cached_tree_ = tree;
    cached_cloud_ = cloud_tgt.get();
    cached_fingerprint_ = fingerprint;
  }
  return cached_tree_;
}

template <typename PointSource, typename PointTarget, typename Scalar>
pcl::fot::PsiResult TransformationValidationPsi<PointSource, PointTarget, Scalar>::score(
    const PointCloudSourceConstPtr& cloud_src, const PointCloudTargetConstPtr& cloud_tgt,
    const Matrix4& transformation_matrix) const {
  if (!cloud_src || !cloud_tgt)
    throw std::invalid_argument("pcl::fot::registration::TransformationValidationPsi: no cloud");
  const std::shared_ptr<const pcl::fot::FastOctTree> target = targetTree(cloud_tgt);
  pcl::PointCloud<PointSource> moved;
  pcl::transformPointCloud(*cloud_src, moved, transformation_matrix);
  pcl::fot::FastOctTree source(target->getGrid());
  pcl::fot::insertPointCloud(source, moved);
  if (source.empty() || target->empty()) {  // nothing to compare, capped or not
    pcl::fot::PsiResult none;
    none.defined = false;
    none.resolution = resolution_;
    return none;
  }
  pcl::fot::PsiOptions options;
  const double cap_cells = std::ceil(max_range_ / resolution_);
  if (cap_cells > 0 && cap_cells < 0x1p62) options.cap = std::int64_t(cap_cells);  // larger caps nothing
  return pcl::fot::psi(source, *target, options);
}

template <typename PointSource, typename PointTarget, typename Scalar>
double TransformationValidationPsi<PointSource, PointTarget, Scalar>::validateTransformation(
    const PointCloudSourceConstPtr& cloud_src, const PointCloudTargetConstPtr& cloud_tgt,
    const Matrix4& transformation_matrix) const {
  const pcl::fot::PsiResult r = score(cloud_src, cloud_tgt, transformation_matrix);
  // Without a cell on both sides the maps cannot be compared: the worst score, as PCL reports no match.
  if (!r.defined || r.cells == 0) return DBL_MAX;
  return r.meanMetres();
}

template <typename PointSource, typename PointTarget, typename Scalar>
bool TransformationValidationPsi<PointSource, PointTarget, Scalar>::isValid(
    const PointCloudSourceConstPtr& cloud_src, const PointCloudTargetConstPtr& cloud_tgt,
    const Matrix4& transformation_matrix) const {
  if (std::isnan(threshold_)) {
    PCL_ERROR(
        "[pcl::fot::registration::TransformationValidationPsi::isValid] The threshold is unset: call "
        "setThreshold.\n");
    return false;
  }
  return validateTransformation(cloud_src, cloud_tgt, transformation_matrix) < threshold_;
}

}  // namespace registration
}  // namespace fot
}  // namespace pcl
