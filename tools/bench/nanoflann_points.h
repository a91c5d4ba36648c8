#pragma once
// nanoflann's dataset adaptors for the benchmarks, and its static tree over packed points.

#include <cstddef>
#include <vector>

#include <nanoflann.hpp>

namespace fot_bench {

/** nanoflann's dataset adaptor over packed xyz floats. */
struct Points {
  std::vector<float> xyz;
  std::size_t kdtree_get_point_count() const { return xyz.size() / 3; }
  float kdtree_get_pt(std::size_t i, std::size_t d) const { return xyz[3 * i + d]; }
  template <typename Box>
  bool kdtree_get_bbox(Box&) const {
    return false;
  }
};

/** nanoflann's dataset adaptor over `count` points of three floats, `stride` floats apart. */
struct StridedPoints {
  const float* xyz = nullptr;
  std::size_t stride = 3, count = 0;
  std::size_t kdtree_get_point_count() const { return count; }
  float kdtree_get_pt(std::size_t i, std::size_t d) const { return xyz[stride * i + d]; }
  template <typename Box>
  bool kdtree_get_bbox(Box&) const {
    return false;
  }
};

template <typename Distance>
using NanoTree = nanoflann::KDTreeSingleIndexAdaptor<Distance, Points, 3, unsigned>;

}  // namespace fot_bench
