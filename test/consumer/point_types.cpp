// The templates with the point types users bring: their own (PCL_NO_PRECOMPILE, as PCL asks for custom
// types), a different type for source and target, and double-precision transformations.
#define PCL_NO_PRECOMPILE
#include <cstdint>
#include <iostream>

#include <pcl/point_types.h>
#include <pcl/register_point_struct.h>
#include <pcl/registration/icp.h>
#include <pcl_fot/pcl/octree/octree_point_cloud.h>
#include <pcl_fot/pcl/registration/correspondence_rejection_psi.h>
#include <pcl_fot/pcl/registration/transformation_validation_psi.h>
#include <pcl_fot/pcl/search/fast_oct_tree_search.h>

struct EIGEN_ALIGN16 LidarPoint {
  PCL_ADD_POINT4D;
  float intensity;
  std::uint16_t ring;
  PCL_MAKE_ALIGNED_OPERATOR_NEW
};
POINT_CLOUD_REGISTER_POINT_STRUCT(LidarPoint, (float, x, x)(float, y, y)(float, z, z)(
                                                  float, intensity, intensity)(std::uint16_t, ring, ring))

namespace {

int failures = 0;

void expect(bool ok, const char* what) {
  std::cout << (ok ? "ok:   " : "FAIL: ") << what << "\n";
  failures += ok ? 0 : 1;
}

}  // namespace

int main() {
  // A bent 40 × 40 sheet, 1 cm apart.
  pcl::PointCloud<LidarPoint>::Ptr sheet(new pcl::PointCloud<LidarPoint>);
  pcl::PointCloud<pcl::PointNormal>::Ptr shifted(new pcl::PointCloud<pcl::PointNormal>);
  for (int i = 0; i < 40; ++i)
    for (int j = 0; j < 40; ++j) {
      LidarPoint p;
      p.x = 0.01f * float(i), p.y = 0.01f * float(j), p.z = 0.0005f * float(i * i), p.intensity = 1,
      p.ring = 0;
      sheet->push_back(p);
      pcl::PointNormal q;
      q.x = p.x + 0.1f, q.y = p.y, q.z = p.z;
      shifted->push_back(q);
    }

  pcl::fot::search::FastOctTreeSearch<LidarPoint>::Ptr search(
      new pcl::fot::search::FastOctTreeSearch<LidarPoint>(0.02));
  search->setInputCloud(sheet);
  pcl::Indices k;
  std::vector<float> d;
  search->nearestKSearch((*sheet)[777], 5, k, d);
  expect(k.size() == 5 && k[0] == 777 && d[0] == 0.0f && d[4] > 0.0f, "k-NN on a custom point type");

  pcl::fot::OctreePointCloud<LidarPoint> octree(0.05);
  octree.setInputCloud(sheet);
  octree.addPointsFromInputCloud();
  expect(octree.getLeafCount() > 0 && octree.isVoxelOccupiedAtPoint((*sheet)[0]), "OctreePointCloud on it");

  pcl::fot::registration::TransformationValidationPsi<LidarPoint, pcl::PointNormal> mixed(0.05);
  const double apart = mixed.validateTransformation(sheet, shifted, Eigen::Matrix4f::Identity());
  Eigen::Matrix4f back = Eigen::Matrix4f::Identity();
  back(0, 3) = 0.1f;
  const double together = mixed.validateTransformation(sheet, shifted, back);
  expect(together == 0.0 && apart > 0.0, "ψ with different source and target types");

  pcl::fot::registration::TransformationValidationPsi<LidarPoint, pcl::PointNormal, double> precise(0.05);
  expect(precise.validateTransformation(sheet, shifted, back.cast<double>()) == together &&
             precise.validateTransformation(sheet, shifted, Eigen::Matrix4d::Identity()) == apart,
         "ψ with double transformations");

  pcl::IterativeClosestPoint<LidarPoint, LidarPoint> icp;
  pcl::PointCloud<LidarPoint>::Ptr moved(new pcl::PointCloud<LidarPoint>(*sheet));
  for (auto& p : *moved) p.x += 0.02f;
  auto rejector = pcl::make_shared<pcl::fot::registration::CorrespondenceRejectorPsi<LidarPoint>>(0.02, 1.0);
  icp.setInputSource(moved);
  icp.setInputTarget(sheet);
  icp.setSearchMethodTarget(search);
  icp.addCorrespondenceRejector(rejector);
  pcl::PointCloud<LidarPoint> aligned;
  icp.align(aligned);
  expect(icp.hasConverged() && !rejector->history().empty() &&
             rejector->history().back() < rejector->history().front(),
         "ICP with the search and the ψ rejector on a custom point type");

  std::cout << (failures ? "point types: failed\n" : "point types: all passed\n");
  return failures ? 1 : 0;
}
