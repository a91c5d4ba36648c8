#pragma once

#include <cstdint>
#include <vector>

#include <pcl/octree/octree_key.h>

namespace pcl {
namespace fot {

/**
 * Which of a set of voxels touch which: for each voxel, the voxels of the set among the 27 around it, itself
 * included, in pcl::octree's order (the x offset from -1 to 1, then y's, then z's). The adjacency octree
 * links its leaves by it. The keys are sorted once and swept row by row (a row: one x and y), each of the
 * nine rows around a voxel followed by a cursor that only moves forward: no look-up per neighbour.
 */
class VoxelNeighbors {
 public:
  /** `keys` must be distinct. */
  explicit VoxelNeighbors(const std::vector<octree::OctreeKey>& keys);

  /** The neighbours of voxel i, as indices into the keys, in pcl::octree's order. */
  const std::uint32_t* begin(std::size_t i) const { return index_.data() + first_[i]; }
  const std::uint32_t* end(std::size_t i) const { return index_.data() + last_[i]; }

 private:
  std::vector<std::uint32_t> index_;
  std::vector<std::uint32_t> first_, last_;  // each voxel's range in index_
};

}  // namespace fot
}  // namespace pcl
