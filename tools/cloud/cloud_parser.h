#pragma once
// PCD and PLY point cloud files parsed from their bytes: x, y, z and the sensor pose, nothing else.
// Not PCL's readers: on damaged files they crash (PCD) or abort on an assertion (PLY).

#include <cstddef>
#include <cstdint>
#include <stdexcept>
#include <vector>

namespace fot_tools {

/** What the tools use of a point cloud file. */
struct XyzCloud {
  std::vector<float> xyz;  // width × height points, row by row; values beyond float's range become ±inf
  std::uint32_t width = 0, height = 0;
  float origin[3] = {0, 0, 0};
  float orientation[4] = {1, 0, 0, 0};  // w, x, y, z, as the file gives it
};

/** A file that cannot be used; what() completes the sentence "'<file>' ...". */
struct CloudFileError : std::runtime_error {
  using std::runtime_error::runtime_error;
};

/**
 * A .pcd file: ascii, binary or binary_compressed, as PCL's PCDReader reads it; x, y, z must be floats or
 * doubles. The sensor pose is the VIEWPOINT. Throws CloudFileError; never allocates more than the file's
 * data can fill.
 */
XyzCloud parsePcd(const char* bytes, std::size_t size);

/**
 * A .ply file: ascii, binary_little_endian or binary_big_endian; x, y, z of the vertex element, floats or
 * doubles. The pose and organised size come from the camera element PCL writes (PCL's own reader loses the
 * pose), or obj_info num_cols / num_rows; a range_grid element makes the cloud organised, with NaN points
 * in its empty cells. Throws CloudFileError; never allocates more than the file's data can fill.
 */
XyzCloud parsePly(const char* bytes, std::size_t size);

}  // namespace fot_tools
