#include "fragg_map/sensor_model.h"

#include <Eigen/Geometry>
#include <algorithm>
#include <cmath>
#include <sstream>

#include "fragg_map/errors.h"

namespace fragg {

namespace {
constexpr double kDeg = M_PI / 180.0;

bool validPoint(const Eigen::Vector3f& p) {
  return std::isfinite(p.x()) && std::isfinite(p.y()) && std::isfinite(p.z()) &&
         p.squaredNorm() > 0.f;
}

/// Rounds an angle up to whole degrees so that similar clouds resolve to the same model (and
/// culling can reuse rejections across scans).
double ceilDeg(double rad) { return std::ceil(rad / kDeg - 1e-9) * kDeg; }
double floorDeg(double rad) { return std::floor(rad / kDeg + 1e-9) * kDeg; }
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
}

std::string SensorModel::describe() const {
  std::ostringstream s;
  s.precision(4);
  s << toString(type);
  if (type == SensorType::kPinhole)
    s << " hfov=" << hfov_rad / kDeg << "deg vfov=" << vfov_rad / kDeg << "deg";
  if (type == SensorType::kSpinningLidar)
    s << " elevation=[" << elevation_min_rad / kDeg << ", " << elevation_max_rad / kDeg << "]deg";
  s << " range=[" << min_range_m << ", ";
  if (max_range_m > 0.0)
    s << max_range_m << "]m";
  else
    s << "unlimited]";
  if (range_noise_m > 0.0 || range_noise_quadratic_per_m > 0.0)
    s << " noise=" << range_noise_m << "m+" << range_noise_quadratic_per_m << "/m*r^2";
  return s.str();
}

namespace {
/// The pyramid's basis for an axis: `right` from a hint that is not parallel to it.
void pinholeBasis(const Eigen::Vector3d& axis, Eigen::Vector3d* right, Eigen::Vector3d* vertical) {
  const Eigen::Vector3d hint =
      std::fabs(axis.z()) < 0.9 ? Eigen::Vector3d(0, 0, 1) : Eigen::Vector3d(0, 1, 0);
  *right = hint.cross(axis).normalized();
  *vertical = axis.cross(*right);
}

const double kMinForward = std::cos(85 * kDeg);  // wider than 170 degrees: a lidar

/// The pinhole fit of a cloud around an axis: every valid point in front of it (by more than
/// kMinForward of its range) and the largest tangents across `right` and `vertical`.
struct AxisFit {
  bool fits = true;
  double tan_h = 0.0, tan_v = 0.0;
  void merge(const AxisFit& o) {
    fits = fits && o.fits;
    tan_h = std::max(tan_h, o.tan_h);
    tan_v = std::max(tan_v, o.tan_v);
  }
};

/// The six sensor axes (+x, -x, +y, -y, +z, -z), to which a camera cloud's axis snaps: their
/// bases are sensor axes too, so a point's dot products with them are single coordinates
/// (exactly: the other terms are products with 0), and the fit around each can be gathered in
/// the same pass that finds the axis.
struct SensorAxes {
  Eigen::Vector3d axis[6];
  int along[6], across_h[6], across_v[6];  ///< coordinate of the axis, of right, of vertical
  double sign[6];
  SensorAxes() {
    for (int k = 0; k < 6; ++k) {
      axis[k] = Eigen::Vector3d::Zero();
      along[k] = k / 2;
      sign[k] = k % 2 ? -1.0 : 1.0;
      axis[k][along[k]] = sign[k];
      Eigen::Vector3d right, vertical;
      pinholeBasis(axis[k], &right, &vertical);
      right.cwiseAbs().maxCoeff(&across_h[k]);
      vertical.cwiseAbs().maxCoeff(&across_v[k]);
    }
  }
  /// One valid point `d` at range `r` into the fits around every axis still fitting.
  void add(const Eigen::Vector3d& d, double r, AxisFit* fit) const {
    const double forward_min = kMinForward * r;
    for (int k = 0; k < 6; ++k) {
      AxisFit& f = fit[k];
      if (!f.fits) continue;
      const double z = sign[k] * d[along[k]];
      if (z <= forward_min) {
        f.fits = false;
        continue;
      }
      f.tan_h = raiseTangent(f.tan_h, std::fabs(d[across_h[k]]), z);
      f.tan_v = raiseTangent(f.tan_v, std::fabs(d[across_v[k]]), z);
    }
  }
  /// max(tan, across / z) for z > 0, dividing only when the ratio may exceed `tan`: a ratio
  /// whose rounded quotient is above `tan` is above it exactly, so across > tan * z, and the
  /// product's rounding (half an ulp) stays far inside the 1e-12 slack. The same maximum as
  /// dividing every time, to the bit.
  static double raiseTangent(double tan, double across, double z) {
    if (across < tan * z * (1.0 - 1e-12)) return tan;
    return std::max(tan, across / z);
  }
};
const SensorAxes kSensorAxes;

/// The fit around any axis: a second pass over the points.
AxisFit fitAround(const PointCloud& cloud, const Eigen::Vector3d& axis,
                  const Eigen::Vector3d& right, const Eigen::Vector3d& vertical) {
  double tan_h = 0.0, tan_v = 0.0;
  bool fits = true;
  const long n = static_cast<long>(cloud.points_S.size());
#pragma omp parallel for schedule(static) reduction(max : tan_h, tan_v) reduction(&& : fits)
  for (long i = 0; i < n; ++i) {
    const Eigen::Vector3f& p = cloud.points_S[i];
    if (!fits || !validPoint(p)) continue;
    const Eigen::Vector3d d = p.cast<double>();
    const double z = d.dot(axis);
    if (z <= kMinForward * d.norm()) {
      fits = false;
      continue;
    }
    tan_h = std::max(tan_h, std::fabs(d.dot(right)) / z);
    tan_v = std::max(tan_v, std::fabs(d.dot(vertical)) / z);
  }
  AxisFit f;
  f.fits = fits;
  f.tan_h = tan_h;
  f.tan_v = tan_v;
  return f;
}
}  // namespace

SensorModel resolveAutoSensor(const SensorModel& model, const PointCloud& cloud) {
  // Runs once per scan over every point: only products, one division and a square root per
  // point; the angles come from the extreme ratios at the end (atan and asin are monotonic).
  // In parallel over a fixed number of chunks, summed in chunk order: the same result for
  // any thread count. Elevation extremes come along for the LiDAR case, and the pinhole fits
  // around the six sensor axes for a camera cloud whose axis snaps to one (a second pass over
  // the points is needed only for an axis that does not).
  SensorModel out = model;
  constexpr int kChunks = 64;
  struct Partial {
    double max_dist = 0.0, sin_min = 1.0, sin_max = -1.0;
    Eigen::Vector3d dir_sum = Eigen::Vector3d::Zero();
    size_t valid = 0;
    AxisFit fit[6];
  };
  Partial part[kChunks];
  const size_t n = cloud.points_S.size();
#pragma omp parallel for schedule(static)
  for (int c = 0; c < kChunks; ++c) {
    Partial q;  // on this thread's stack: no cache line shared with another chunk's
    for (size_t i = n * c / kChunks; i < n * (c + 1) / kChunks; ++i) {
      const Eigen::Vector3f& p = cloud.points_S[i];
      if (!validPoint(p)) continue;
      const Eigen::Vector3d d = p.cast<double>();
      const double r = d.norm();
      const double inv_r = 1.0 / r;
      q.max_dist = std::max(q.max_dist, r);
      q.dir_sum += d * inv_r;
      const double s = std::clamp(d.z() * inv_r, -1.0, 1.0);
      q.sin_min = std::min(q.sin_min, s);
      q.sin_max = std::max(q.sin_max, s);
      ++q.valid;
      kSensorAxes.add(d, r, q.fit);
    }
    part[c] = q;
  }
  double max_dist = 0.0, sin_min = 1.0, sin_max = -1.0;
  Eigen::Vector3d mean_dir = Eigen::Vector3d::Zero();
  size_t valid = 0;
  AxisFit axis_fit[6];
  for (const Partial& q : part) {
    max_dist = std::max(max_dist, q.max_dist);
    sin_min = std::min(sin_min, q.sin_min);
    sin_max = std::max(sin_max, q.sin_max);
    mean_dir += q.dir_sum;
    valid += q.valid;
    for (int k = 0; k < 6; ++k) axis_fit[k].merge(q.fit[k]);
  }
  if (out.max_range_m <= 0.0) out.max_range_m = std::max(1.0, std::ceil(max_dist));
  if (valid == 0) {  // nothing to see: a lidar model keeps culling well defined
    out.type = SensorType::kSpinningLidar;
    out.elevation_min_rad = -M_PI / 2;
    out.elevation_max_rad = M_PI / 2;
    return out;
  }
  // A pinhole pyramid around the mean direction when every point lies well in front of the
  // sensor; otherwise (the points surround it, or the pyramid would be too wide) a LiDAR shell.
  Eigen::Vector3d axis = mean_dir / static_cast<double>(valid);
  if (axis.norm() > 0.3) {
    axis.normalize();
    // Snap to a sensor axis when close, so camera clouds keep the same frustum scan to scan.
    int snapped = -1;
    for (int k = 0; k < 6; ++k)
      if (axis.dot(kSensorAxes.axis[k]) > std::cos(3 * kDeg)) {
        axis = kSensorAxes.axis[k];
        snapped = k;
      }
    Eigen::Vector3d right, vertical;
    pinholeBasis(axis, &right, &vertical);
    const AxisFit fit = snapped >= 0 ? axis_fit[snapped] : fitAround(cloud, axis, right, vertical);
    // One degree of slack, rounded up to whole degrees.
    const double hfov = ceilDeg(2 * std::atan(fit.tan_h) + 2 * kDeg);
    const double vfov = ceilDeg(2 * std::atan(fit.tan_v) + 2 * kDeg);
    if (fit.fits && hfov < 170 * kDeg && vfov < 170 * kDeg) {
      out.type = SensorType::kPinhole;
      out.hfov_rad = hfov;
      out.vfov_rad = vfov;
      out.forward_S = axis;
      out.right_S = right;
      return out;
    }
  }
  out.type = SensorType::kSpinningLidar;
  out.elevation_min_rad = std::max(-M_PI / 2, floorDeg(std::asin(sin_min) - kDeg));
  out.elevation_max_rad = std::min(M_PI / 2, ceilDeg(std::asin(sin_max) + kDeg));
  return out;
}

double frustumVoxelEstimate(double fov_rad, double depth_m, double near_m, double resolution_m) {
  const double t = std::tan(fov_rad / 2.0);
  const double s1 = M_PI / 4.0 * (t * near_m) * (t * near_m);
  const double s2 = M_PI / 4.0 * (t * (near_m + depth_m)) * (t * (near_m + depth_m));
  const double volume = depth_m / 3.0 * (s1 + s2 + std::sqrt(s1 * s2));
  return volume / (resolution_m * resolution_m * resolution_m);
}

}  // namespace fragg
