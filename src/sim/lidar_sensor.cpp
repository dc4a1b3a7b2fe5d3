#include "fragg_map/sim/lidar_sensor.h"

#include <cmath>
#include <limits>

#include "fragg_map/errors.h"
#include "fragg_map/sim/random.h"
#include "sensor_rays.h"

namespace fragg::sim {

constexpr uint64_t kStreamLidar = 0x11da7;

void LidarSpec::validate() const {
  if (beams < 1 || beams > 4096) throw InvalidArgument("lidar: beams must be in [1, 4096]");
  if (azimuth_steps < 1 || azimuth_steps > 100000)
    throw InvalidArgument("lidar: azimuth steps must be in [1, 100000]");
  if (!(elevation_min_deg >= -90 && elevation_max_deg <= 90 &&
        elevation_min_deg <= elevation_max_deg))
    throw InvalidArgument("lidar: need -90 <= elevation min <= elevation max <= 90 degrees");
  if (!(min_range_m >= 0 && max_range_m > min_range_m))
    throw InvalidArgument("lidar: need 0 <= min range < max range");
  if (!(range_noise_m >= 0)) throw InvalidArgument("lidar: range noise must be >= 0");
  if (!(dropout >= 0 && dropout <= 1)) throw InvalidArgument("lidar: dropout must be in [0, 1]");
}

Eigen::Vector3f LidarSpec::direction(int beam, int column) const {
  const double el_deg =
      beams == 1 ? elevation_max_deg
                 : elevation_max_deg - (elevation_max_deg - elevation_min_deg) * beam / (beams - 1);
  const double el = el_deg * M_PI / 180.0, az = 2.0 * M_PI * column / azimuth_steps;
  return Eigen::Vector3d(std::cos(el) * std::cos(az), std::cos(el) * std::sin(az), std::sin(el))
      .cast<float>();
}

PointCloud simulateLidar(const geometry::MeshBvh& scene, const LidarSpec& spec,
                         const Eigen::Isometry3d& T_map_sensor, uint64_t seed, uint64_t frame,
                         const geometry::MeshBvh* movers, std::vector<uint8_t>* dynamic_labels) {
  spec.validate();
  PointCloud cloud;
  cloud.width = static_cast<uint32_t>(spec.azimuth_steps);
  cloud.height = static_cast<uint32_t>(spec.beams);
  const int64_t n = int64_t{spec.beams} * spec.azimuth_steps;
  cloud.points_S.assign(n, Eigen::Vector3f::Constant(std::numeric_limits<float>::quiet_NaN()));
  if (dynamic_labels) dynamic_labels->assign(n, 0);
  const Eigen::Matrix3f R = T_map_sensor.linear().cast<float>();
  const Eigen::Vector3f origin = T_map_sensor.translation().cast<float>();
  const uint64_t frame_key = randomKey(seed, kStreamLidar, frame);
#pragma omp parallel for schedule(dynamic, 4096)
  for (int64_t i = 0; i < n; ++i) {
    const int beam = static_cast<int>(i / spec.azimuth_steps);
    const int column = static_cast<int>(i % spec.azimuth_steps);
    const Eigen::Vector3f d_S = spec.direction(beam, column);
    geometry::RayHit hit;
    bool dynamic = false;
    if (!nearestHit(scene, movers, origin, R * d_S, static_cast<float>(spec.max_range_m), &hit,
                    &dynamic))
      continue;
    if (hit.t_m < spec.min_range_m) continue;
    const uint64_t key = mix64(frame_key ^ static_cast<uint64_t>(i));
    if (spec.dropout > 0 && uniform01(key) < spec.dropout) continue;
    const double range =
        hit.t_m + (spec.range_noise_m > 0 ? spec.range_noise_m * gaussian(mix64(key)) : 0.0);
    if (!(range > spec.min_range_m && range < spec.max_range_m)) continue;
    cloud.points_S[i] = d_S * static_cast<float>(range);
    if (dynamic_labels) (*dynamic_labels)[i] = dynamic ? 1 : 0;
  }
  return cloud;
}

}  // namespace fragg::sim
