#pragma once

#include <cmath>
#include <cstddef>
#include <functional>
#include <limits>
#include <map>
#include <vector>

#include <boost/graph/adjacency_list.hpp>

#include <pcl/common/point_tests.h>
#include <pcl/console/print.h>

#include <pcl_fot/pcl/octree/octree_point_cloud.h>
#include <pcl_fot/pcl/octree/voxel_neighbors.h>

namespace pcl {
namespace fot {

/**
 * pcl::octree::OctreePointCloudAdjacency: the octree of a whole cloud in a box fitted to it (through an
 * optional transform of each point), each voxel linked to its occupied neighbours among the 26 around it.
 * begin()/end() run over the leaves' containers in PCL's leaf order, as PCL's do.
 */
template <typename PointT, typename LeafContainerT = OctreePointCloudAdjacencyContainer<PointT>,
          typename BranchContainerT = OctreeContainerEmpty>
class OctreePointCloudAdjacency : public OctreePointCloud<PointT, LeafContainerT, BranchContainerT> {
 public:
  using OctreePointCloudT = OctreePointCloud<PointT, LeafContainerT, BranchContainerT>;
  using Ptr = shared_ptr<OctreePointCloudAdjacency<PointT, LeafContainerT, BranchContainerT>>;
  using ConstPtr = shared_ptr<const OctreePointCloudAdjacency<PointT, LeafContainerT, BranchContainerT>>;
  using typename OctreePointCloudT::LeafNode;
  using typename OctreePointCloudT::PointCloud;
  using typename OctreePointCloudT::PointCloudConstPtr;
  using typename OctreePointCloudT::PointCloudPtr;
  using VoxelAdjacencyList =
      boost::adjacency_list<boost::setS, boost::setS, boost::undirectedS, PointT, float>;
  using VoxelID = typename VoxelAdjacencyList::vertex_descriptor;
  using EdgeID = typename VoxelAdjacencyList::edge_descriptor;
  using LeafVectorT = std::vector<LeafContainerT*>;
  using iterator = typename LeafVectorT::iterator;
  using const_iterator = typename LeafVectorT::const_iterator;

  OctreePointCloudAdjacency(const double resolution_arg) : OctreePointCloudT(resolution_arg) {}

  iterator begin() { return leaf_vector_.begin(); }
  iterator end() { return leaf_vector_.end(); }
  LeafContainerT* at(std::size_t idx) { return leaf_vector_.at(idx); }
  std::size_t size() const { return leaf_vector_.size(); }

  /** Fits the box to the (transformed) finite points, adds them all, then links each voxel to its neighbours.
   */
  void addPointsFromInputCloud() {
    if (!this->input_) {
      PCL_ERROR("[pcl::fot::OctreePointCloudAdjacency::addPointsFromInputCloud] No input cloud.\n");
      return;
    }
    float lo[3], hi[3];
    std::fill(lo, lo + 3, std::numeric_limits<float>::max());
    std::fill(hi, hi + 3, -std::numeric_limits<float>::max());
    for (const PointT& point : *this->input_) {
      PointT p = transformed(point);
      if (!isFinite(p)) continue;
      const float c[3] = {p.x, p.y, p.z};
      for (int a = 0; a < 3; ++a) {
        lo[a] = std::min(lo[a], c[a]);
        hi[a] = std::max(hi[a], c[a]);
      }
    }
    if (lo[0] > hi[0]) return;  // no finite point
    this->defineBoundingBox(lo[0], lo[1], lo[2], hi[0], hi[1], hi[2]);
    OctreePointCloudT::addPointsFromInputCloud();
    leaf_vector_.clear();
    leaf_vector_.reserve(this->getLeafCount());
    std::vector<octree::OctreeKey> keys;
    keys.reserve(this->getLeafCount());
    for (auto it = this->leaf_depth_begin(); it != this->leaf_depth_end(); ++it) {
      LeafContainerT* leaf = &it.getLeafContainer();
      leaf->computeData();
      keys.push_back(it.getCurrentOctreeKey());
      leaf_vector_.push_back(leaf);
    }
    const VoxelNeighbors neighbors(keys);
    for (std::size_t i = 0; i < leaf_vector_.size(); ++i)
      for (const std::uint32_t* n = neighbors.begin(i); n != neighbors.end(i); ++n)
        leaf_vector_[i]->addNeighbor(leaf_vector_[*n]);
  }

  /** The container of the (transformed) point's voxel; nullptr if it has none. */
  LeafContainerT* getLeafContainerAtPoint(const PointT& point_arg) const {
    const PointT p = transformed(point_arg);
    if (!isFinite(p) || !this->isPointWithinBoundingBox(p.x, p.y, p.z)) return nullptr;
    LeafNode* leaf = this->findLeaf(this->pclKey(p.x, p.y, p.z));
    return leaf ? leaf->getContainerPtr() : nullptr;
  }

  /** One vertex per voxel (its centre), one edge per pair of neighbours weighted by their distance. */
  void computeVoxelAdjacencyGraph(VoxelAdjacencyList& voxel_adjacency_graph) {
    voxel_adjacency_graph.clear();
    std::map<LeafContainerT*, VoxelID> vertex_of;
    for (auto it = this->leaf_depth_begin(); it != this->leaf_depth_end(); ++it) {
      PointT center;
      this->pclKeyToCenter(it.getCurrentOctreeKey(), center);
      const VoxelID id = add_vertex(voxel_adjacency_graph);
      voxel_adjacency_graph[id] = center;
      vertex_of[&it.getLeafContainer()] = id;
    }
    for (LeafContainerT* leaf : leaf_vector_) {
      const VoxelID u = vertex_of.at(leaf);
      const PointT p_u = voxel_adjacency_graph[u];
      for (auto n = leaf->cbegin(); n != leaf->cend(); ++n) {
        const VoxelID v = vertex_of.at(static_cast<LeafContainerT*>(*n));
        const float distance = (voxel_adjacency_graph[v].getVector3fMap() - p_u.getVector3fMap()).norm();
        voxel_adjacency_graph[add_edge(u, v, distance, voxel_adjacency_graph).first] = distance;
      }
    }
  }

  void setTransformFunction(std::function<void(PointT& p)> transform_func) {
    transform_func_ = transform_func;
  }

  /**
   * Whether an occupied voxel lies between the point's voxel and the camera: PCL's walk in steps of one
   * voxel from the voxel's centre; the walk ends where it leaves the box.
   */
  bool testForOcclusion(const PointT& point_arg, const PointXYZ& camera_pos = PointXYZ(0, 0, 0)) {
    const PointT start = transformed(point_arg);
    if (!isFinite(start) || !this->isPointWithinBoundingBox(start.x, start.y, start.z)) return false;
    const octree::OctreeKey key = this->pclKey(start.x, start.y, start.z);
    PointT center;
    this->pclKeyToCenter(key, center);
    const Eigen::Vector3f sensor(camera_pos.x, camera_pos.y, camera_pos.z);
    Eigen::Vector3f p(center.x, center.y, center.z);
    Eigen::Vector3f direction = sensor - p;
    const float norm = direction.norm();
    if (!std::isfinite(norm)) return false;
    direction.normalize();
    const auto step = static_cast<float>(this->getResolution());
    const auto steps = std::max<std::size_t>(1, static_cast<std::size_t>(norm / step));
    octree::OctreeKey previous = key;
    for (std::size_t i = 0; i < steps; ++i) {
      p += direction * step;
      PointT q;
      q.x = p.x();
      q.y = p.y();
      q.z = p.z();
      if (!this->isPointWithinBoundingBox(q.x, q.y, q.z)) return false;
      const octree::OctreeKey k = this->pclKey(q.x, q.y, q.z);
      if (k == previous) continue;
      previous = k;
      if (this->findLeaf(k)) return true;
    }
    return false;
  }

 protected:
  /** The (transformed) point's count goes to its leaf; the box is already fitted, so it never grows. */
  void addPointIdx(uindex_t point_idx_arg) override {
    const PointT& point = (*this->input_)[point_idx_arg];
    const PointT p = transformed(point);
    if (!isFinite(point) || !isFinite(p) || !this->isPointWithinBoundingBox(p.x, p.y, p.z)) return;
    this->createLeaf(this->pclKey(p.x, p.y, p.z))->getContainer().addPoint(point);
  }

  /**
   * Links the leaf to every leaf among the 27 voxels around its key, itself included, in PCL's order: PCL's
   * protected call for one leaf. The build links all leaves at once (VoxelNeighbors).
   */
  void computeNeighbors(const octree::OctreeKey& key, LeafContainerT* leaf) {
    const uindex_t last = static_cast<uindex_t>((std::uint64_t(1) << this->getTreeDepth()) - 1);
    for (int dx = key.x > 0 ? -1 : 0; dx <= (key.x == last ? 0 : 1); ++dx)
      for (int dy = key.y > 0 ? -1 : 0; dy <= (key.y == last ? 0 : 1); ++dy)
        for (int dz = key.z > 0 ? -1 : 0; dz <= (key.z == last ? 0 : 1); ++dz)
          if (LeafNode* neighbor = this->findLeaf(octree::OctreeKey(key.x + dx, key.y + dy, key.z + dz)))
            leaf->addNeighbor(neighbor->getContainerPtr());
  }

 private:
  PointT transformed(const PointT& point) const {
    PointT p(point);
    if (transform_func_) transform_func_(p);
    return p;
  }

  LeafVectorT leaf_vector_;
  std::function<void(PointT& p)> transform_func_;
};

}  // namespace fot
}  // namespace pcl
