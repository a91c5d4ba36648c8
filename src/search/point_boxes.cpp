#include <pcl_fot/search/point_boxes.h>

#include <algorithm>

namespace pcl {
namespace fot {
namespace detail {

namespace {

void split(BucketPoint* points, std::uint32_t first, std::uint32_t begin, std::uint32_t end,
           std::vector<PointBox>& boxes) {
  const std::size_t node = boxes.size();
  const BucketPoint& a = points[begin];
  PointBox box{{a.p[0], a.p[1], a.p[2]}, {a.p[0], a.p[1], a.p[2]}, first + begin, first + end, 0, a.index};
  for (std::uint32_t i = begin + 1; i < end; ++i) {
    for (int d = 0; d < 3; ++d)
      box.lo[d] = std::min(box.lo[d], points[i].p[d]), box.hi[d] = std::max(box.hi[d], points[i].p[d]);
    box.least_index = std::min(box.least_index, points[i].index);
  }
  boxes.push_back(box);
  if (end - begin <= kCrowdLeaf) return;
  int axis = 0;
  for (int d = 1; d < 3; ++d)
    if (box.hi[d] - box.lo[d] > box.hi[axis] - box.lo[axis]) axis = d;
  const std::uint32_t mid = begin + (end - begin) / 2;
  std::nth_element(points + begin, points + mid, points + end,
                   [axis](const BucketPoint& u, const BucketPoint& v) {
                     return u.p[axis] < v.p[axis] || (u.p[axis] == v.p[axis] && u.index < v.index);
                   });
  split(points, first, begin, mid, boxes);
  boxes[node].right = std::uint32_t(boxes.size());
  split(points, first, mid, end, boxes);
}

}  // namespace

void splitIntoBoxes(BucketPoint* points, std::uint32_t count, std::uint32_t first,
                    std::vector<PointBox>& boxes) {
  if (count > 0) split(points, first, 0, count, boxes);
}

}  // namespace detail
}  // namespace fot
}  // namespace pcl
