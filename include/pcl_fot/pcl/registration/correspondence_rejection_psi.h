#pragma once

#include <cstddef>
#include <functional>
#include <vector>

#include <pcl/conversions.h>
#include <pcl/registration/correspondence_rejection.h>
#include <pcl/registration/default_convergence_criteria.h>

#include <pcl_fot/pcl/registration/transformation_validation_psi.h>

namespace pcl {
namespace fot {
namespace registration {

/**
 * Scores every ICP iteration with ψ (see TransformationValidationPsi) and rejects nothing: add it with
 * icp.addCorrespondenceRejector(). ICP hands it the target once and, each iteration, the source as the
 * current estimate moves it and the correspondences it found, before the step is taken. Read history()
 * afterwards, or get each score as it comes with setCallback(), next to the mean squared distance of the
 * correspondences (ICP's own error); PsiConvergenceCriteria can stop ICP on ψ.
 */
template <typename PointT>
class CorrespondenceRejectorPsi : public pcl::registration::CorrespondenceRejector {
 public:
  using Ptr = shared_ptr<CorrespondenceRejectorPsi<PointT>>;
  using ConstPtr = shared_ptr<const CorrespondenceRejectorPsi<PointT>>;
  using Validation = TransformationValidationPsi<PointT, PointT>;

  explicit CorrespondenceRejectorPsi(double resolution = 0.05, double max_range = 1.0)
      : validation_(resolution, max_range) {
    rejection_name_ = "CorrespondenceRejectorPsi";
  }

  bool requiresSourcePoints() const override { return true; }
  void setSourcePoints(pcl::PCLPointCloud2::ConstPtr cloud2) override;
  bool requiresTargetPoints() const override { return true; }
  void setTargetPoints(pcl::PCLPointCloud2::ConstPtr cloud2) override;

  void getRemainingCorrespondences(const pcl::Correspondences& original,
                                   pcl::Correspondences& remaining) override {
    remaining = original;
  }

  /** ψ (the validation's score) at each iteration, in order. */
  const std::vector<double>& history() const { return history_; }
  using Callback = std::function<void(std::size_t iteration, double psi, double correspondence_mse)>;
  void setCallback(Callback callback) { callback_ = std::move(callback); }
  const Validation& validation() const { return validation_; }

 protected:
  /** Scores the iteration, then passes every correspondence on. */
  void applyRejection(pcl::Correspondences& correspondences) override;

 private:
  Validation validation_;
  typename pcl::PointCloud<PointT>::Ptr source_, target_;
  std::vector<double> history_;
  Callback callback_;
};

template <typename PointT>
void CorrespondenceRejectorPsi<PointT>::setTargetPoints(pcl::PCLPointCloud2::ConstPtr cloud2) {
  target_.reset(new pcl::PointCloud<PointT>);
  pcl::fromPCLPointCloud2(*cloud2, *target_);
  history_.clear();
}

template <typename PointT>
void CorrespondenceRejectorPsi<PointT>::setSourcePoints(pcl::PCLPointCloud2::ConstPtr cloud2) {
  source_.reset(new pcl::PointCloud<PointT>);
  pcl::fromPCLPointCloud2(*cloud2, *source_);
}

template <typename PointT>
void CorrespondenceRejectorPsi<PointT>::applyRejection(pcl::Correspondences& correspondences) {
  correspondences = *input_correspondences_;
  if (!source_ || !target_) {
    PCL_ERROR("[pcl::fot::registration::CorrespondenceRejectorPsi] ICP gave no source or target points.\n");
    return;
  }
  const double psi = validation_.validateTransformation(source_, target_, Eigen::Matrix4f::Identity());
  history_.push_back(psi);
  if (!callback_) return;
  double mse = 0;
  for (const auto& c : correspondences) mse += c.distance;
  callback_(history_.size() - 1, psi, correspondences.empty() ? 0.0 : mse / double(correspondences.size()));
}

/**
 * ICP's default convergence tests plus one on ψ: converged when the last ψ a CorrespondenceRejectorPsi
 * recorded is below an absolute threshold (reported as CONVERGENCE_CRITERIA_ABS_MSE), or improved on the
 * one before by less than a relative fraction (reported as CONVERGENCE_CRITERIA_REL_MSE). Install it in
 * place of ICP's own, from which it takes ICP's counters:
 *   icp.convergence_criteria_ = pcl::make_shared<PsiConvergenceCriteria<float>>(*icp.getConvergeCriteria(),
 * rejector_history);
 */
template <typename Scalar = float>
class PsiConvergenceCriteria : public pcl::registration::DefaultConvergenceCriteria<Scalar> {
 public:
  using Base = pcl::registration::DefaultConvergenceCriteria<Scalar>;

  /** `history`: a CorrespondenceRejectorPsi's history(), read at every check. */
  PsiConvergenceCriteria(const Base& defaults, const std::vector<double>& history)
      : Base(defaults), history_(history) {}

  void setPsiThreshold(double psi) { psi_threshold_ = psi; }
  double getPsiThreshold() const { return psi_threshold_; }
  void setRelativePsiImprovement(double fraction) { relative_improvement_ = fraction; }
  double getRelativePsiImprovement() const { return relative_improvement_; }

  bool hasConverged() override {
    const std::size_t n = history_.size();
    if (n >= 1 && history_[n - 1] < psi_threshold_) {
      this->setConvergenceState(Base::CONVERGENCE_CRITERIA_ABS_MSE);
      return true;
    }
    if (n >= 2 && history_[n - 2] > 0 &&
        history_[n - 2] - history_[n - 1] < relative_improvement_ * history_[n - 2] &&
        history_[n - 1] <= history_[n - 2]) {
      this->setConvergenceState(Base::CONVERGENCE_CRITERIA_REL_MSE);
      return true;
    }
    return Base::hasConverged();
  }

 private:
  const std::vector<double>& history_;
  double psi_threshold_ = 0.0;
  double relative_improvement_ = 0.0;
};

}  // namespace registration
}  // namespace fot
}  // namespace pcl
