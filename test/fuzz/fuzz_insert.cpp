// Insertion itself: a scan (points, sensor pose, resolution, max range, sensor model and ray
// caster from the input bytes) through Map::insert on the CPU backend, then, with the scan kept,
// a second insertion, a pose correction and a removal. The errors a caller catches
// (InvalidArgument for bad arguments) are fine; a crash, a sanitizer report or a broken invariant
// is a finding: the statistics must account for every point, and no block may lie beyond the
// max range (plus a block) from the sensor.
//
// Layout (little-endian; a short input is padded with zero bytes):
//   byte 0   flags: bit 0 Bresenham, bits 1-2 sensor (0 auto, 1 lidar, 2 pinhole, 3 auto), bit 3
//            keep scans (then insert again, correct and remove), bit 4 organised cloud with
//            no-return clearing, bit 5 a range noise, bit 6 skip saturated blocks off
//   byte 1   resolution: 0-3 pick 0.01 / 0.05 / 0.2 / 1 m, otherwise the float32 at bytes 2-5
//   bytes 2-5    float32 resolution (when byte 1 > 3)
//   bytes 6-9    float32 max range (<= 0: none, the farthest point)
//   bytes 10-37  float32 sensor position x y z, quaternion w x y z (normalised; unusable:
//                identity rotation)
//   bytes 38-    float32 points x y z (at most kMaxPoints)
#include <Eigen/Geometry>
#include <cmath>
#include <cstdlib>
#include <cstring>
#include <map>

#include "fragg_map/errors.h"
#include "fragg_map/map.h"
#include "fuzz_targets.h"

namespace fragg::fuzz {

namespace {

constexpr size_t kHeaderBytes = 38;
constexpr size_t kMaxPoints = 512;

float floatAt(const uint8_t* data, size_t size, size_t at) {
  uint8_t bytes[4] = {0, 0, 0, 0};
  for (size_t i = 0; i < 4; ++i)
    if (at + i < size) bytes[i] = data[at + i];
  float v;
  std::memcpy(&v, bytes, 4);
  return v;
}

/// A broken invariant: abort, so that libFuzzer (and the corpus replay) reports the input.
void check(bool ok) {
  if (!ok) std::abort();
}

/// Every point of `s` counted once: a ray (hit, free-only, no return) or a drop.
void checkPointsAccountedFor(const InsertStats& s, size_t points) {
  const uint64_t counted = s.rays_hit + s.rays_free_only + s.rays_no_return + s.dropped_invalid +
                           s.dropped_min_range + s.dropped_outside_frustum + s.dropped_height;
  check(s.points_in == points && counted == points);
}

/// No block farther than the max range (and one block's diagonal) from the sensor's position.
void checkBlocksWithinRange(const Map& map, const Eigen::Vector3d& sensor_m, double max_range_m) {
  if (!(max_range_m > 0.0)) return;
  const double block_m = map.resolution() * kBlockSize;
  const double reach_m = max_range_m + 2.0 * std::sqrt(3.0) * block_m;
  map.forEachBlock([&](const BlockKey& key, const Block&) {
    const Eigen::Vector3d centre_m =
        (Eigen::Vector3d(key.x, key.y, key.z).array() + 0.5).matrix() * block_m;
    check((centre_m - sensor_m).norm() <= reach_m);
  });
}

}  // namespace

int insertScan(const uint8_t* data, size_t size) {
  if (size < 1) return 0;
  const uint8_t flags = data[0];
  const uint8_t res_byte = size > 1 ? data[1] : 0;
  static const double kResolutions[4] = {0.01, 0.05, 0.2, 1.0};
  const double resolution_m =
      res_byte < 4 ? kResolutions[res_byte] : static_cast<double>(floatAt(data, size, 2));
  const double max_range_m = floatAt(data, size, 6);
  float pose[7];
  for (int i = 0; i < 7; ++i) pose[i] = floatAt(data, size, 10 + 4 * static_cast<size_t>(i));

  PointCloud cloud;
  const size_t n = size > kHeaderBytes ? std::min((size - kHeaderBytes) / 12, kMaxPoints) : 0;
  for (size_t i = 0; i < n; ++i) {
    const size_t at = kHeaderBytes + 12 * i;
    cloud.points_S.emplace_back(floatAt(data, size, at), floatAt(data, size, at + 4),
                                floatAt(data, size, at + 8));
  }
  const bool organised = (flags & 0x10) != 0 && n >= 2;
  if (organised) {
    cloud.width = static_cast<uint32_t>(n / 2);
    cloud.height = 2;
    cloud.points_S.resize(2 * static_cast<size_t>(cloud.width));
  }

  MapParams params;
  params.backend = Backend::kCpu;
  params.threads = 1;
  params.resolution_m = resolution_m;
  params.raycast = (flags & 1) ? RayCast::kBresenham : RayCast::kDda;
  params.scans.keep = (flags & 0x08) != 0;
  params.clear_no_return_rays = organised;
  params.skip_saturated_blocks = (flags & 0x40) == 0;

  SensorModel sensor;
  const double range_arg = max_range_m > 0.0 || !std::isfinite(max_range_m) ? max_range_m : -1.0;
  switch ((flags >> 1) & 3) {
    case 1:
      sensor = SensorModel::spinningLidar(-0.5, 0.5, 0.0, range_arg);
      break;
    case 2:
      sensor = SensorModel::pinhole(1.5, 1.0, 0.0, range_arg);
      break;
    default:
      sensor = SensorModel::autoFromCloud(0.0, range_arg);
      break;
  }
  if (flags & 0x20) sensor.range_noise_m = 0.02;

  Eigen::Isometry3d T_map_sensor = Eigen::Isometry3d::Identity();
  Eigen::Quaterniond q(pose[3], pose[4], pose[5], pose[6]);
  if (std::isfinite(q.norm()) && q.norm() > 1e-3) T_map_sensor.linear() = q.normalized().matrix();
  T_map_sensor.translation() = Eigen::Vector3d(pose[0], pose[1], pose[2]);

  try {
    Map map(params);
    const InsertStats first = map.insert(cloud, T_map_sensor, sensor);
    checkPointsAccountedFor(first, cloud.size());
    const double used_range_m = first.sensor.max_range_m;
    checkBlocksWithinRange(map, T_map_sensor.translation(), used_range_m);
    if (params.scans.keep && !organised) {
      // A second scan a little further on, then both moved and the first taken out again.
      Eigen::Isometry3d T_second = T_map_sensor;
      T_second.translation() += Eigen::Vector3d(0.3, -0.2, 0.1);
      map.insert(cloud, T_second, sensor);
      Eigen::Isometry3d T_corrected = T_map_sensor;
      T_corrected.translation() += Eigen::Vector3d(-0.1, 0.25, 0.05);
      map.correctPoses({{first.scan_id, T_corrected}});
      map.remove(first.scan_id);
    }
  } catch (const InvalidArgument&) {
  }
  return 0;
}

}  // namespace fragg::fuzz
