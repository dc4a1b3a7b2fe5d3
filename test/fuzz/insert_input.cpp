#include "insert_input.h"

#include <algorithm>
#include <cmath>
#include <cstring>

namespace fragg::fuzz {

namespace {

constexpr size_t kHeaderBytes = 38;

float floatAt(const uint8_t* data, size_t size, size_t at) {
  uint8_t bytes[4] = {0, 0, 0, 0};
  for (size_t i = 0; i < 4; ++i)
    if (at + i < size) bytes[i] = data[at + i];
  float v;
  std::memcpy(&v, bytes, 4);
  return v;
}

}  // namespace

InsertInput decodeInsertInput(const uint8_t* data, size_t size) {
  InsertInput in;
  const uint8_t flags = size > 0 ? data[0] : 0;
  const uint8_t res_byte = size > 1 ? data[1] : 0;
  static const double kResolutions[4] = {0.01, 0.05, 0.2, 1.0};
  const double resolution_m =
      res_byte < 4 ? kResolutions[res_byte] : static_cast<double>(floatAt(data, size, 2));
  const double max_range_m = floatAt(data, size, 6);
  float pose[7];
  for (int i = 0; i < 7; ++i) pose[i] = floatAt(data, size, 10 + 4 * static_cast<size_t>(i));

  const size_t n = size > kHeaderBytes ? std::min((size - kHeaderBytes) / 12, kMaxInsertPoints) : 0;
  for (size_t i = 0; i < n; ++i) {
    const size_t at = kHeaderBytes + 12 * i;
    Eigen::Vector3f p(floatAt(data, size, at), floatAt(data, size, at + 4),
                      floatAt(data, size, at + 8));
    const double range_v = p.cast<double>().norm() / resolution_m;
    if (std::isfinite(range_v) && range_v > kMaxInsertRayV && range_v < 67108864.0)
      p = (p.cast<double>() * (kMaxInsertRayV / range_v)).cast<float>();
    in.cloud.points_S.push_back(p);
  }
  const bool organised = (flags & 0x10) != 0 && n >= 2;
  if (organised) {
    in.cloud.width = static_cast<uint32_t>(n / 2);
    in.cloud.height = 2;
    in.cloud.points_S.resize(2 * static_cast<size_t>(in.cloud.width));
  }

  MapParams& params = in.params;
  params.backend = Backend::kCpu;
  params.threads = 1;
  params.resolution_m = resolution_m;
  params.raycast = (flags & 1) ? RayCast::kBresenham : RayCast::kDda;
  params.scans.keep = (flags & 0x08) != 0;
  params.clear_no_return_rays = organised;
  params.skip_saturated_blocks = (flags & 0x40) == 0;
  in.correct_and_remove = params.scans.keep && !organised;

  // <= 0: no limit; NaN and infinities go to the model's own check.
  double range_arg = max_range_m > 0.0 || !std::isfinite(max_range_m) ? max_range_m : -1.0;
  if (range_arg > kMaxInsertRayV * resolution_m) range_arg = kMaxInsertRayV * resolution_m;
  switch ((flags >> 1) & 3) {
    case 1:
      in.sensor = SensorModel::spinningLidar(-0.5, 0.5, 0.0, range_arg);
      break;
    case 2:
      in.sensor = SensorModel::pinhole(1.5, 1.0, 0.0, range_arg);
      break;
    default:
      in.sensor = SensorModel::autoFromCloud(0.0, range_arg);
      break;
  }
  if (flags & 0x20) in.sensor.range_noise_m = 0.02;

  const Eigen::Quaterniond q(pose[3], pose[4], pose[5], pose[6]);
  if (std::isfinite(q.norm()) && q.norm() > 1e-3)
    in.T_map_sensor.linear() = q.normalized().toRotationMatrix();
  in.T_map_sensor.translation() = Eigen::Vector3d(pose[0], pose[1], pose[2]);
  return in;
}

void correctAndRemove(const InsertInput& in, ScanId first, Map& map) {
  if (!in.correct_and_remove) return;
  Eigen::Isometry3d T_second = in.T_map_sensor;
  T_second.translation() += Eigen::Vector3d(0.3, -0.2, 0.1);
  map.insert(in.cloud, T_second, in.sensor);
  Eigen::Isometry3d T_corrected = in.T_map_sensor;
  T_corrected.translation() += Eigen::Vector3d(-0.1, 0.25, 0.05);
  map.correctPoses({{first, T_corrected}});
  map.remove(first);
}

InsertStats runInsertInput(const InsertInput& in, Map& map) {
  const InsertStats first = map.insert(in.cloud, in.T_map_sensor, in.sensor);
  correctAndRemove(in, first.scan_id, map);
  return first;
}

}  // namespace fragg::fuzz
