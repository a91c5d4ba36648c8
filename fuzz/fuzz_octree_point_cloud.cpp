// Fuzz target: pcl::fot::OctreePointCloud against pcl::octree::OctreePointCloudOccupancy, call for call. The
// input picks a resolution, a bounding box (none, a box or a cube) and a scale for the coordinates, then
// sets, deletes and queries voxels at points on a grid finer than the voxels, so that many lie on voxel
// faces. Both must give the same answer to every query, and agree afterwards on the depth, the bounding box,
// the nodes of every iterator in order, the voxel centres and bounds, and the branch count. A point that
// pcl::octree would fail an assertion on (inside the box, but rounding past its last voxel) ends the
// comparison: ours must then hold it in the box's last voxel.
#include <cstdint>
#include <cstdlib>
#include <vector>

#include <pcl/common/point_tests.h>  // PCL 1.13's occupancy header uses isFinite without including it
#include <pcl/octree/octree_pointcloud_occupancy.h>

#include <pcl_fot/pcl/octree/octree_point_cloud.h>

namespace {

using pcl::PointXYZ;

void check(bool ok) {
  if (!ok) std::abort();
}

bool samePoint(const PointXYZ& a, const PointXYZ& b) {
  return a.x == b.x && a.y == b.y && a.z == b.z;
}

/**
 * Whether `p` lies in the box but rounds to a key past its last voxel: pcl::octree fails an assertion on
 * such a point, where ours takes the last voxel. The boxes are equal, so ours tells.
 */
bool pclWouldAssert(const pcl::fot::OctreePointCloud<PointXYZ>& ours, const PointXYZ& p) {
  double box[6];
  ours.getBoundingBox(box[0], box[1], box[2], box[3], box[4], box[5]);
  const double c[3] = {p.x, p.y, p.z}, side = double(std::uint64_t(1) << ours.getTreeDepth());
  bool inside = true, past = false;
  for (int a = 0; a < 3; ++a) {
    inside = inside && c[a] >= box[a] && c[a] < box[a + 3];
    past = past || (c[a] - box[a]) / ours.getResolution() >= side;
  }
  return inside && past;
}

}  // namespace

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
  static const double kResolutions[] = {0.01, 0.05, 0.1, 0.25, 1.0, 0.003, 0.7, 2.5};
  static const double kScales[] = {0.25, 0.5, 1.0, 0.37};  // coordinates are multiples of this many cells
  if (size < 4) return 0;
  const double res = kResolutions[data[0] & 7];
  const double step = res * kScales[(data[0] >> 3) & 3];
  const int box = (data[0] >> 5) & 3;
  pcl::octree::OctreePointCloudOccupancy<PointXYZ> theirs(res);
  pcl::fot::OctreePointCloud<PointXYZ> ours(res);
  if (box == 1) {  // a box from the next three bytes, around the origin
    const double lo[3] = {-double(data[1] % 64) * step, -double(data[2] % 64) * step,
                          -double(data[3] % 64) * step};
    const double hi[3] = {lo[0] + (1 + data[1] / 4) * step, lo[1] + (1 + data[2] / 4) * step,
                          lo[2] + (1 + data[3] / 4) * step};
    theirs.defineBoundingBox(lo[0], lo[1], lo[2], hi[0], hi[1], hi[2]);
    ours.defineBoundingBox(lo[0], lo[1], lo[2], hi[0], hi[1], hi[2]);
  } else if (box == 2) {
    theirs.defineBoundingBox((1 + data[1]) * step);
    ours.defineBoundingBox((1 + data[1]) * step);
  }

  // Each 4 bytes: the operation, then a point as three multiples of the step.
  std::vector<PointXYZ> points;
  for (std::size_t i = 4; i + 4 <= size; i += 4) {
    const PointXYZ p(float(std::int8_t(data[i + 1]) * step), float(std::int8_t(data[i + 2]) * step),
                     float(std::int8_t(data[i + 3]) * step));
    points.push_back(p);
    const int op = data[i] % 4;
    if (op < 2) ours.setOccupiedVoxelAtPoint(p);  // first: its box is then the one pcl::octree would have
    if (pclWouldAssert(ours, p)) {                // ours must still keep its voxels inside the box
      check(op >= 2 || ours.isVoxelOccupiedAtPoint(p));
      const std::uint64_t side = std::uint64_t(1) << ours.getTreeDepth();
      for (auto it = ours.leaf_depth_begin(); it != ours.leaf_depth_end(); ++it) {
        const pcl::octree::OctreeKey& k = it.getCurrentOctreeKey();
        check(k.x < side && k.y < side && k.z < side);
      }
      return 0;
    }
    switch (op) {
      case 0:
      case 1:
        theirs.setOccupiedVoxelAtPoint(p);
        break;
      case 2:
        theirs.deleteVoxelAtPoint(p);
        ours.deleteVoxelAtPoint(p);
        break;
      default:
        check(theirs.isVoxelOccupiedAtPoint(p) == ours.isVoxelOccupiedAtPoint(p));
    }
  }

  check(theirs.getTreeDepth() == ours.getTreeDepth());
  check(theirs.getLeafCount() == ours.getLeafCount());
  check(theirs.getBranchCount() == ours.getBranchCount());
  check(theirs.getVoxelSquaredSideLen() == ours.getVoxelSquaredSideLen());
  double a[6], b[6];
  theirs.getBoundingBox(a[0], a[1], a[2], a[3], a[4], a[5]);
  ours.getBoundingBox(b[0], b[1], b[2], b[3], b[4], b[5]);
  for (int k = 0; k < 6; ++k) check(a[k] == b[k]);
  for (const PointXYZ& p : points) check(theirs.isVoxelOccupiedAtPoint(p) == ours.isVoxelOccupiedAtPoint(p));

  // Every iterator, node by node: key, depth, kind, children and bounds.
  auto sameNodes = [&](auto begin, auto end) {
    auto t = begin(theirs);
    auto o = begin(ours);
    for (; t != end(theirs); ++t, ++o) {
      check(o != end(ours));
      check(t.getCurrentOctreeKey() == o.getCurrentOctreeKey());
      check(t.getCurrentOctreeDepth() == o.getCurrentOctreeDepth());
      check(t.isLeafNode() == o.isLeafNode() && t.getNodeConfiguration() == o.getNodeConfiguration());
      Eigen::Vector3f tmin, tmax, omin, omax;
      theirs.getVoxelBounds(t, tmin, tmax);
      ours.getVoxelBounds(o, omin, omax);
      check(tmin == omin && tmax == omax);
    }
    check(o == end(ours));
  };
  const pcl::uindex_t cut = data[1] % (ours.getTreeDepth() + 1);
  sameNodes([](auto& x) { return x.leaf_depth_begin(); }, [](auto& x) { return x.leaf_depth_end(); });
  sameNodes([](auto& x) { return x.begin(); }, [](auto& x) { return x.end(); });
  sameNodes([&](auto& x) { return x.breadth_begin(cut); }, [](auto& x) { return x.breadth_end(); });
  sameNodes([&](auto& x) { return x.fixed_depth_begin(cut); }, [](auto& x) { return x.fixed_depth_end(); });

  pcl::octree::OctreePointCloudOccupancy<PointXYZ>::AlignedPointTVector tc;
  pcl::fot::OctreePointCloud<PointXYZ>::AlignedPointTVector oc;
  check(theirs.getOccupiedVoxelCenters(tc) == ours.getOccupiedVoxelCenters(oc) && tc.size() == oc.size());
  for (std::size_t k = 0; k < tc.size(); ++k) check(samePoint(tc[k], oc[k]));

  return 0;
}
