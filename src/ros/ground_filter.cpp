#include "fragg_map/ros/ground_filter.h"

#include <pcl/ModelCoefficients.h>
#include <pcl/PointIndices.h>
#include <pcl/point_cloud.h>
#include <pcl/point_types.h>
#include <pcl/sample_consensus/method_types.h>
#include <pcl/sample_consensus/model_types.h>
#include <pcl/segmentation/sac_segmentation.h>

#include <cmath>
#include <vector>

namespace fragg::ros {

namespace {
constexpr size_t kMinPoints = 50;     // octomap_server: smaller clouds are not segmented
constexpr size_t kMinRemaining = 10;  // ... and it stops when no more than 10 points remain
constexpr int kIterations = 200;
}  // namespace

GroundSplit markGroundPoints(const Eigen::Isometry3d& T_base_sensor,
                             const GroundFilterParams& params, PointCloud* cloud) {
  GroundSplit split;
  // The candidates in the base frame, with their index in the cloud.
  pcl::PointCloud<pcl::PointXYZ>::Ptr remaining(new pcl::PointCloud<pcl::PointXYZ>);
  std::vector<size_t> index;
  remaining->reserve(cloud->size());
  index.reserve(cloud->size());
  for (size_t i = 0; i < cloud->size(); ++i) {
    const Eigen::Vector3f& p_S = cloud->points_S[i];
    if (!p_S.allFinite() || p_S.squaredNorm() == 0.f) continue;
    const Eigen::Vector3f p_B = (T_base_sensor * p_S.cast<double>()).cast<float>();
    remaining->push_back(pcl::PointXYZ(p_B.x(), p_B.y(), p_B.z()));
    index.push_back(i);
  }
  split.points = index.size();
  if (split.points < kMinPoints) return split;
  if (cloud->free_only.size() != cloud->size()) cloud->free_only.assign(cloud->size(), 0);
  const std::vector<float> z_B = [&] {
    std::vector<float> z(remaining->size());
    for (size_t k = 0; k < z.size(); ++k) z[k] = (*remaining)[k].z;
    return z;
  }();
  const std::vector<size_t> all_index = index;

  pcl::SACSegmentation<pcl::PointXYZ> seg;
  seg.setOptimizeCoefficients(true);
  seg.setModelType(pcl::SACMODEL_PERPENDICULAR_PLANE);
  seg.setMethodType(pcl::SAC_RANSAC);
  seg.setMaxIterations(kIterations);
  seg.setDistanceThreshold(params.distance_m);
  seg.setAxis(Eigen::Vector3f::UnitZ());
  seg.setEpsAngle(params.angle_rad);
  pcl::ModelCoefficients coefficients;
  pcl::PointIndices inliers;
  while (remaining->size() > kMinRemaining && !split.plane_found) {
    seg.setInputCloud(remaining);
    seg.segment(inliers, coefficients);
    if (inliers.indices.empty() || coefficients.values.size() != 4) break;
    const bool ground = std::fabs(coefficients.values[3]) < params.plane_distance_m;
    std::vector<uint8_t> is_inlier(remaining->size(), 0);
    for (const int k : inliers.indices) is_inlier[static_cast<size_t>(k)] = 1;
    if (ground) {
      for (size_t k = 0; k < is_inlier.size(); ++k)
        if (is_inlier[k]) cloud->free_only[index[k]] = 1;
      split.ground = inliers.indices.size();
      split.plane_found = true;
      break;
    }
    // Another horizontal plane (a table, a ceiling): not ground; look again without it.
    ++split.other_planes;
    pcl::PointCloud<pcl::PointXYZ>::Ptr rest(new pcl::PointCloud<pcl::PointXYZ>);
    std::vector<size_t> rest_index;
    rest->reserve(remaining->size() - inliers.indices.size());
    for (size_t k = 0; k < is_inlier.size(); ++k)
      if (!is_inlier[k]) {
        rest->push_back((*remaining)[k]);
        rest_index.push_back(index[k]);
      }
    remaining = rest;
    index.swap(rest_index);
  }
  if (!split.plane_found) {
    // No ground plane: octomap_server's rough fallback, a height band around z = 0.
    for (size_t k = 0; k < all_index.size(); ++k)
      if (z_B[k] >= -params.plane_distance_m && z_B[k] <= params.plane_distance_m) {
        cloud->free_only[all_index[k]] = 1;
        ++split.ground;
      }
  }
  return split;
}

}  // namespace fragg::ros
