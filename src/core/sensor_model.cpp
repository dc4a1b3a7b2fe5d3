#include "fragg_map/sensor_model.h"

#include <Eigen/Geometry>
#include <algorithm>
#include <cmath>
#include <sstream>

#include "fragg_map/errors.h"

namespace fragg {

namespace {
constexpr double kRadPerDeg = M_PI / 180.0;
}  // namespace

const char* toString(SensorType t) {
  switch (t) {
    case SensorType::kSpinningLidar:
      return "lidar";
    case SensorType::kPinhole:
      return "pinhole";
    case SensorType::kAuto:
      break;
  }
  return "auto";
}

SensorType sensorTypeFromString(const std::string& s) {
  if (s == "auto") return SensorType::kAuto;
  if (s == "lidar" || s == "spinning_lidar") return SensorType::kSpinningLidar;
  if (s == "pinhole" || s == "depth") return SensorType::kPinhole;
  throw InvalidArgument("sensor.type must be auto, lidar or pinhole, got '" + s + "'");
}

SensorModel SensorModel::autoFromCloud(double min_range_m, double max_range_m) {
  SensorModel m;
  m.type = SensorType::kAuto;
  m.min_range_m = min_range_m;
  m.max_range_m = max_range_m;
  return m;
}

SensorModel SensorModel::pinhole(double hfov_rad, double vfov_rad, double min_range_m,
                                 double max_range_m, OpticalAxis axis) {
  SensorModel m;
  m.type = SensorType::kPinhole;
  m.hfov_rad = hfov_rad;
  m.vfov_rad = vfov_rad;
  m.min_range_m = min_range_m;
  m.max_range_m = max_range_m;
  m.optical_axis = axis;
  if (axis == OpticalAxis::kXForward) {
    m.forward_S = Eigen::Vector3d::UnitX();
    m.right_S = -Eigen::Vector3d::UnitY();
  }
  return m;
}

SensorModel SensorModel::spinningLidar(double elevation_min_rad, double elevation_max_rad,
                                       double min_range_m, double max_range_m) {
  SensorModel m;
  m.type = SensorType::kSpinningLidar;
  m.elevation_min_rad = elevation_min_rad;
  m.elevation_max_rad = elevation_max_rad;
  m.min_range_m = min_range_m;
  m.max_range_m = max_range_m;
  return m;
}

// Messages name the field as `sensor.<member>` (front ends rename it: field_names.h).
void SensorModel::validate() const {
  if (!std::isfinite(min_range_m) || min_range_m < 0.0)
    throw InvalidArgument("sensor.min_range_m must be >= 0 m, got " + std::to_string(min_range_m));
  if (!std::isfinite(max_range_m))
    throw InvalidArgument("sensor.max_range_m must be finite (or <= 0 for no limit)");
  if (max_range_m > 0.0 && max_range_m <= min_range_m)
    throw InvalidArgument("sensor.max_range_m must exceed sensor.min_range_m (or be <= 0)");
  if (!(range_noise_m >= 0.0 && range_noise_m <= kMaxRangeNoiseM))  // NaN fails too
    throw InvalidArgument("sensor.range_noise_m must be in [0, " + std::to_string(kMaxRangeNoiseM) +
                          "] m, got " + std::to_string(range_noise_m));
  if (!(range_noise_quadratic_per_m >= 0.0 &&
        range_noise_quadratic_per_m <= kMaxRangeNoiseQuadraticPerM))
    throw InvalidArgument("sensor.range_noise_quadratic_per_m must be in [0, " +
                          std::to_string(kMaxRangeNoiseQuadraticPerM) + "] per m, got " +
                          std::to_string(range_noise_quadratic_per_m));
  if (type == SensorType::kPinhole) {
    if (!(hfov_rad > 0.0 && hfov_rad < M_PI))
      throw InvalidArgument(
          "sensor.hfov_rad must be in (0, pi) rad (0-180 degrees) for a pinhole, got " +
          std::to_string(hfov_rad) + " rad");
    if (!(vfov_rad > 0.0 && vfov_rad < M_PI))
      throw InvalidArgument(
          "sensor.vfov_rad must be in (0, pi) rad (0-180 degrees) for a pinhole, got " +
          std::to_string(vfov_rad) + " rad");
    if (std::fabs(forward_S.norm() - 1.0) > 1e-6 || std::fabs(right_S.norm() - 1.0) > 1e-6 ||
        std::fabs(forward_S.dot(right_S)) > 1e-6)
      throw InvalidArgument("sensor.forward_S and sensor.right_S must be orthonormal");
  }
  if (type == SensorType::kSpinningLidar) {
    if (!(elevation_min_rad >= -M_PI / 2 - 1e-9 && elevation_min_rad <= M_PI / 2 + 1e-9))
      throw InvalidArgument(
          "sensor.elevation_min_rad must be in [-pi/2, pi/2] rad (+-90 degrees), got " +
          std::to_string(elevation_min_rad) + " rad");
    if (!(elevation_max_rad >= -M_PI / 2 - 1e-9 && elevation_max_rad <= M_PI / 2 + 1e-9))
      throw InvalidArgument(
          "sensor.elevation_max_rad must be in [-pi/2, pi/2] rad (+-90 degrees), got " +
          std::to_string(elevation_max_rad) + " rad");
    if (elevation_min_rad >= elevation_max_rad)
      throw InvalidArgument("sensor.elevation_min_rad must be below sensor.elevation_max_rad");
  }
  lidar_beams.validate();
  if (!lidar_beams.empty()) {
    if (type == SensorType::kPinhole)
      throw InvalidArgument("sensor.lidar_rings: a beam table needs a lidar (or auto) sensor");
    if (type == SensorType::kSpinningLidar &&
        (lidar_beams.ring_elevations_rad.front() < elevation_min_rad - 1e-9 ||
         lidar_beams.ring_elevations_rad.back() > elevation_max_rad + 1e-9))
      throw InvalidArgument("sensor.lidar_ring_elevations_rad: the rings span [" +
                            std::to_string(lidar_beams.ring_elevations_rad.front()) + ", " +
                            std::to_string(lidar_beams.ring_elevations_rad.back()) +
                            "] rad, outside sensor.elevation_min_rad..sensor.elevation_max_rad");
  }
}

std::string SensorModel::describe() const {
  std::ostringstream s;
  s.precision(4);
  s << toString(type);
  if (type == SensorType::kPinhole)
    s << " hfov=" << hfov_rad / kRadPerDeg << "deg vfov=" << vfov_rad / kRadPerDeg << "deg";
  if (type == SensorType::kSpinningLidar)
    s << " elevation=[" << elevation_min_rad / kRadPerDeg << ", " << elevation_max_rad / kRadPerDeg
      << "]deg";
  s << " range=[" << min_range_m << ", ";
  if (max_range_m > 0.0)
    s << max_range_m << "]m";
  else
    s << "unlimited]";
  if (!lidar_beams.empty()) s << " beams=" << lidar_beams.rings() << "x" << lidar_beams.columns;
  if (range_noise_m > 0.0 || range_noise_quadratic_per_m > 0.0)
    s << " noise=" << range_noise_m << "m+" << range_noise_quadratic_per_m << "/m*r^2";
  return s.str();
}

double frustumVoxelEstimate(double fov_rad, double depth_m, double near_m, double resolution_m) {
  const double t = std::tan(fov_rad / 2.0);
  const double s1 = M_PI / 4.0 * (t * near_m) * (t * near_m);
  const double s2 = M_PI / 4.0 * (t * (near_m + depth_m)) * (t * (near_m + depth_m));
  const double volume = depth_m / 3.0 * (s1 + s2 + std::sqrt(s1 * s2));
  return volume / (resolution_m * resolution_m * resolution_m);
}

}  // namespace fragg
