#include "fragg_map/sim/depth_camera.h"

#include <cmath>
#include <limits>

#include "fragg_map/errors.h"
#include "fragg_map/sim/random.h"
#include "sensor_rays.h"

namespace fragg::sim {

constexpr uint64_t kStreamDepth = 0xde97;

void DepthCameraSpec::validate() const {
  if (width < 1 || height < 1 || width > 16384 || height > 16384)
    throw InvalidArgument("depth camera: width and height must be in [1, 16384]");
  if (!(hfov_deg > 0 && hfov_deg < 180))
    throw InvalidArgument("depth camera: hfov must be in (0, 180) degrees");
  if (!(min_range_m >= 0 && max_range_m > min_range_m))
    throw InvalidArgument("depth camera: need 0 <= min range < max range");
  if (!(noise_m >= 0)) throw InvalidArgument("depth camera: noise must be >= 0");
  if (!(dropout >= 0 && dropout <= 1))
    throw InvalidArgument("depth camera: dropout must be in [0, 1]");
}

DepthIntrinsics DepthCameraSpec::intrinsics() const {
  DepthIntrinsics k;
  k.fx = k.fy = 0.5 * width / std::tan(0.5 * hfov_deg * M_PI / 180.0);
  k.cx = 0.5 * (width - 1);
  k.cy = 0.5 * (height - 1);
  k.depth_scale_m = 0.001;
  return k;
}

PointCloud simulateDepthCamera(const geometry::MeshBvh& scene, const DepthCameraSpec& spec,
                               const Eigen::Isometry3d& T_map_camera, uint64_t seed, uint64_t frame,
                               const geometry::MeshBvh* movers,
                               std::vector<uint8_t>* dynamic_labels) {
  spec.validate();
  const DepthIntrinsics k = spec.intrinsics();
  PointCloud cloud;
  cloud.width = static_cast<uint32_t>(spec.width);
  cloud.height = static_cast<uint32_t>(spec.height);
  const int64_t n = int64_t{spec.width} * spec.height;
  cloud.points_S.assign(n, Eigen::Vector3f::Constant(std::numeric_limits<float>::quiet_NaN()));
  if (dynamic_labels) dynamic_labels->assign(n, 0);
  const Eigen::Matrix3f R = T_map_camera.linear().cast<float>();
  const Eigen::Vector3f origin = T_map_camera.translation().cast<float>();
  const uint64_t frame_key = randomKey(seed, kStreamDepth, frame);
#pragma omp parallel for schedule(dynamic, 4096)
  for (int64_t i = 0; i < n; ++i) {
    const int u = static_cast<int>(i % spec.width), v = static_cast<int>(i / spec.width);
    const Eigen::Vector3f ray_C((u - k.cx) / k.fx, (v - k.cy) / k.fy, 1.0f);  // z = 1
    const float len = ray_C.norm();
    geometry::RayHit hit;
    const float t_max = static_cast<float>(spec.max_range_m) * len;
    bool dynamic = false;
    if (!nearestHit(scene, movers, origin, R * (ray_C / len), t_max, &hit, &dynamic)) continue;
    double depth = hit.t_m / len;
    if (depth < spec.min_range_m) continue;
    const uint64_t key = mix64(frame_key ^ static_cast<uint64_t>(i));
    if (spec.dropout > 0 && uniform01(key) < spec.dropout) continue;
    if (spec.noise_m > 0) depth += spec.noise_m * depth * depth * gaussian(mix64(key));
    if (!(depth > spec.min_range_m && depth < spec.max_range_m)) continue;
    cloud.points_S[i] = ray_C * static_cast<float>(depth);
    if (dynamic_labels) (*dynamic_labels)[i] = dynamic ? 1 : 0;
  }
  return cloud;
}

DepthImage toDepthImage(const PointCloud& cloud_C, double scale_m) {
  if (!cloud_C.organised()) throw InvalidArgument("depth image: the cloud must be organised");
  DepthImage image;
  image.width = cloud_C.width;
  image.height = cloud_C.height;
  image.depth.resize(cloud_C.size(), 0);
  for (size_t i = 0; i < cloud_C.size(); ++i) {
    const float z = cloud_C.points_S[i].z();
    if (!std::isfinite(z)) continue;
    const long raw = std::lround(z / scale_m);
    if (raw > 0 && raw <= 65535) image.depth[i] = static_cast<uint16_t>(raw);
  }
  return image;
}

}  // namespace fragg::sim
