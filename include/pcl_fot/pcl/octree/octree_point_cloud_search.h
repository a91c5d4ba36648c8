#pragma once

#include <cstdint>
#include <memory>
#include <vector>

#include <pcl_fot/detail/version_cache.h>
#include <pcl_fot/pcl/octree/octree_point_cloud.h>
#include <pcl_fot/search/point_index.h>

namespace pcl {
namespace fot {

/**
 * pcl::octree::OctreePointCloudSearch on a FastOctTree: voxel, k-NN, approximate, radius, box and ray
 * searches with PCL's answers. k-NN searches run on a PointIndex of the octree's points (the engine of
 * FastOctTreeSearch), built at the first search and updated in place as points are added and voxels
 * deleted (a loop that adds a point and searches pays for the point, not for a new index); radius and box
 * searches scan the leaves of the occupied cells around them. Distances are pcl::octree's own floats (Eigen's
 * squaredNorm), bit for bit.
 *
 * Answers are exact: where pcl::octree's float voxel centres are coarser than its voxels (coordinates near
 * 1e6, as in UTM), its pruning can miss points of a k-NN, radius or box search; these do not.
 *
 * Orders, as PCL gives them: k-NN nearest first (ties, which PCL leaves unordered, go to the smaller
 * index); radius and box searches leaf by leaf in PCL's depth-first order, each leaf's points in the
 * order they were added, and max_nn keeps the first ones of that order, as PCL does. approxNearestSearch
 * follows PCL's descent to the leaf whose centre is nearest at each level.
 *
 * Bad input gets PCL_ERROR and an empty answer: a query that is not finite, k = 0, a negative or NaN
 * radius, a search before any point was added. Const searches may run from many threads at once; changing
 * the octree meanwhile is not allowed.
 */
template <typename PointT, typename LeafContainerT = OctreeContainerPointIndices,
          typename BranchContainerT = OctreeContainerEmpty>
class OctreePointCloudSearch : public OctreePointCloud<PointT, LeafContainerT, BranchContainerT> {
 public:
  using OctreeT = OctreePointCloud<PointT, LeafContainerT, BranchContainerT>;
  using Ptr = shared_ptr<OctreePointCloudSearch<PointT, LeafContainerT, BranchContainerT>>;
  using ConstPtr = shared_ptr<const OctreePointCloudSearch<PointT, LeafContainerT, BranchContainerT>>;
  using typename OctreeT::AlignedPointTVector;
  using typename OctreeT::BranchNode;
  using typename OctreeT::IndicesConstPtr;
  using typename OctreeT::IndicesPtr;
  using typename OctreeT::LeafNode;
  using typename OctreeT::PointCloud;
  using typename OctreeT::PointCloudConstPtr;
  using typename OctreeT::PointCloudPtr;

  OctreePointCloudSearch(const double resolution) : OctreeT(resolution) {}

  /** Appends the indices of the points in the voxel of `point`; false if it has no leaf. */
  bool voxelSearch(const PointT& point, Indices& point_idx_data) const;
  bool voxelSearch(uindex_t index, Indices& point_idx_data) const;

  uindex_t nearestKSearch(const PointCloud& cloud, uindex_t index, uindex_t k, Indices& k_indices,
                          std::vector<float>& k_sqr_distances) const {
    return nearestKSearch(cloud[index], k, k_indices, k_sqr_distances);
  }
  uindex_t nearestKSearch(const PointT& p_q, uindex_t k, Indices& k_indices,
                          std::vector<float>& k_sqr_distances) const;
  uindex_t nearestKSearch(uindex_t index, uindex_t k, Indices& k_indices,
                          std::vector<float>& k_sqr_distances) const;

  void approxNearestSearch(const PointCloud& cloud, uindex_t query_index, index_t& result_index,
                           float& sqr_distance) const {
    approxNearestSearch(cloud[query_index], result_index, sqr_distance);
  }
  void approxNearestSearch(const PointT& p_q, index_t& result_index, float& sqr_distance) const;
  void approxNearestSearch(uindex_t query_index, index_t& result_index, float& sqr_distance) const;

  uindex_t radiusSearch(const PointCloud& cloud, uindex_t index, double radius, Indices& k_indices,
                        std::vector<float>& k_sqr_distances, index_t max_nn = 0) const {
    return radiusSearch(cloud[index], radius, k_indices, k_sqr_distances, uindex_t(max_nn));
  }
  uindex_t radiusSearch(const PointT& p_q, const double radius, Indices& k_indices,
                        std::vector<float>& k_sqr_distances, uindex_t max_nn = 0) const;
  uindex_t radiusSearch(uindex_t index, const double radius, Indices& k_indices,
                        std::vector<float>& k_sqr_distances, uindex_t max_nn = 0) const;

  /** The points inside the box, bounds included. */
  uindex_t boxSearch(const Eigen::Vector3f& min_pt, const Eigen::Vector3f& max_pt, Indices& k_indices) const;

  /** As the octree's; the k-NN index of the last search loses the leaf's points in place. */
  void removeLeaf(uindex_t idx_x_arg, uindex_t idx_y_arg, uindex_t idx_z_arg) override;

 protected:
  /** As the octree's; the k-NN index of the last search gains the point in place. */
  void addPointIdx(uindex_t point_idx_arg) override;
  /** The cloud's points go in as the octree's do: the k-NN index is built anew at the next search. */
  bool addsPointsInBulk() const override { return typeid(*this) == typeid(OctreePointCloudSearch); }

 private:
  using typename OctreeT::Slot;

  /** The index of the octree's points, rebuilt when the octree has changed since. */
  std::shared_ptr<const PointIndex> pointIndex() const;
  /**
   * The leaves whose voxels meet the box [lo, hi] (and one voxel around it), in PCL's depth-first order:
   * those a radius or box search visits.
   */
  std::vector<Slot> leavesAround(const Eigen::Vector3d& lo, const Eigen::Vector3d& hi) const;
  /** The input cloud's point at `index`, or nullptr (with PCL_ERROR) if there is none. */
  const PointT* inputPoint(uindex_t index, const char* caller) const;
  /** Whether a query can be answered: the point finite, the octree holding points. */
  bool canSearch(const PointT& p_q, const char* caller) const;

  mutable detail::VersionCache<PointIndex> cache_;  // the index of the octree's points
};

}  // namespace fot
}  // namespace pcl

#ifdef PCL_NO_PRECOMPILE
#include <pcl_fot/pcl/octree/impl/octree_point_cloud_search.hpp>
#endif
