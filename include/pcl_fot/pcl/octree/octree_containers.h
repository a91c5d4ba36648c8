#pragma once

#include <list>

#include <pcl/octree/octree_container.h>
#include <pcl/octree/octree_key.h>
#include <pcl/octree/octree_nodes.h>
#include <pcl/point_types.h>  // registers each type with its point operators (pcl::common)
#include <pcl/types.h>

namespace pcl {
namespace fot {

/**
 * The leaves, nodes and keys of the pcl::octree look-alikes are pcl::octree's own types, so code that names
 * them, or brings its own container with their interface, compiles unchanged.
 */
using octree::BRANCH_NODE;
using octree::LEAF_NODE;
using octree::node_type_t;
using octree::OctreeContainerBase;
using octree::OctreeContainerEmpty;
using octree::OctreeContainerPointIndex;
using octree::OctreeContainerPointIndices;
using octree::OctreeKey;
using octree::OctreeNode;

/** Counts the points of a voxel, as pcl::octree::OctreePointCloudDensityContainer. */
class OctreePointCloudDensityContainer : public OctreeContainerBase {
 public:
  virtual OctreePointCloudDensityContainer* deepCopy() const {
    return new OctreePointCloudDensityContainer(*this);
  }
  bool operator==(const OctreeContainerBase& other) const override {
    const auto* o = dynamic_cast<const OctreePointCloudDensityContainer*>(&other);
    return o && point_counter_ == o->point_counter_;
  }
  void addPointIndex(index_t) override { ++point_counter_; }
  uindex_t getPointCounter() const { return point_counter_; }
  void reset() override { point_counter_ = 0; }

 private:
  uindex_t point_counter_ = 0;
};

/**
 * Sums a voxel's points, as pcl::octree::OctreePointCloudVoxelCentroidContainer: every field with PCL's
 * point operators, so centroids come out bit for bit as PCL's.
 */
template <typename PointT>
class OctreePointCloudVoxelCentroidContainer : public OctreeContainerBase {
 public:
  OctreePointCloudVoxelCentroidContainer() { reset(); }
  virtual OctreePointCloudVoxelCentroidContainer* deepCopy() const {
    return new OctreePointCloudVoxelCentroidContainer(*this);
  }
  bool operator==(const OctreeContainerBase&) const override { return false; }
  void addPoint(const PointT& new_point) {
    using namespace pcl::common;
    ++point_counter_;
    point_sum_ += new_point;
  }
  void getCentroid(PointT& centroid_arg) const {
    using namespace pcl::common;
    if (point_counter_) {
      centroid_arg = point_sum_;
      centroid_arg /= static_cast<float>(point_counter_);
    } else {
      centroid_arg *= 0.0f;
    }
  }
  void reset() override {
    using namespace pcl::common;
    point_counter_ = 0;
    point_sum_ *= 0.0f;
  }

 private:
  uindex_t point_counter_;
  PointT point_sum_;
};

/**
 * A voxel of OctreePointCloudAdjacency, as pcl::octree::OctreePointCloudAdjacencyContainer: its point count,
 * a user datum, and the voxels around it (itself included) that hold points.
 */
template <typename PointInT, typename DataT = PointInT>
class OctreePointCloudAdjacencyContainer : public OctreeContainerBase {
  template <typename T, typename U, typename V>
  friend class OctreePointCloudAdjacency;

 public:
  using NeighborListT = std::list<OctreePointCloudAdjacencyContainer<PointInT, DataT>*>;
  using const_iterator = typename NeighborListT::const_iterator;

  OctreePointCloudAdjacencyContainer() { reset(); }
  const_iterator cbegin() const { return neighbors_.begin(); }
  const_iterator cend() const { return neighbors_.end(); }
  std::size_t size() const { return neighbors_.size(); }
  std::size_t getNumNeighbors() const { return neighbors_.size(); }
  uindex_t getPointCounter() const { return num_points_; }
  DataT& getData() { return data_; }
  void setData(const DataT& data_arg) { data_ = data_arg; }
  uindex_t getSize() const override { return num_points_; }
  void reset() override {
    neighbors_.clear();
    num_points_ = 0;
    data_ = DataT();
  }

 protected:
  using iterator = typename NeighborListT::iterator;
  iterator begin() { return neighbors_.begin(); }
  iterator end() { return neighbors_.end(); }
  void addPoint(const PointInT&) { ++num_points_; }
  /** A hook for containers that derive their datum from their points (supervoxels). */
  void computeData() {}
  void addNeighbor(OctreePointCloudAdjacencyContainer* neighbor) { neighbors_.push_back(neighbor); }
  void removeNeighbor(OctreePointCloudAdjacencyContainer* neighbor) { neighbors_.remove(neighbor); }
  void setNeighbors(const NeighborListT& neighbor_arg) { neighbors_ = neighbor_arg; }
  void setPointCounter(uindex_t points_arg) { num_points_ = points_arg; }

 private:
  uindex_t num_points_;
  NeighborListT neighbors_;
  DataT data_;
};

}  // namespace fot
}  // namespace pcl
