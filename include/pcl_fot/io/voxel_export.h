#pragma once

#include <cstddef>
#include <string>

#include <pcl_fot/tree/fast_oct_tree.h>

namespace pcl {
namespace fot {
namespace io {

enum class VoxelColoring { None, Height, State };

struct VoxelExportOptions {
  bool include_free = false;                       ///< also write free cells
  VoxelColoring coloring = VoxelColoring::Height;  ///< an rgb field, unless None
  std::size_t max_cells = 50'000'000;              ///< refuse maps larger than this rather than fill the disk
};

/**
 * Writes the centres of the occupied (and optionally free) cells as a binary PCD file that pcl_viewer
 * opens as is: fields x y z (rgb), an identity VIEWPOINT so the viewer does not move the cloud, points in
 * the map frame. The write is atomic. Returns the number of points written; throws std::runtime_error on
 * I/O errors and std::length_error beyond options.max_cells.
 */
std::size_t saveVoxelCentersPCD(const FastOctTree& tree, const std::string& path,
                                const VoxelExportOptions& options = {});

/**
 * Writes the voxels as a surface mesh of cubes, a binary legacy VTK file that pcl_viewer opens: one quad
 * per face between an exported voxel and one that is not (inner faces are left out), coloured per point.
 * The write is atomic. Returns the number of faces; throws as saveVoxelCentersPCD.
 */
std::size_t saveVoxelMeshVTK(const FastOctTree& tree, const std::string& path,
                             const VoxelExportOptions& options = {});

}  // namespace io
}  // namespace fot
}  // namespace pcl
