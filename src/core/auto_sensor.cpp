#include "fragg_map/internal/auto_sensor.h"

#include <Eigen/Geometry>
#include <algorithm>
#include <cmath>

namespace fragg {

namespace {
constexpr double kDeg = M_PI / 180.0;
/// A camera cloud's pyramid is around a sensor axis this close to its mean direction.
constexpr double kSnapDeg = 15.0;

/// Rounds an angle up to whole degrees so that similar clouds resolve to the same model (and
/// culling can reuse rejections across scans).
double ceilDeg(double rad) { return std::ceil(rad / kDeg - 1e-9) * kDeg; }
double floorDeg(double rad) { return std::floor(rad / kDeg + 1e-9) * kDeg; }

/// The pyramid's basis for an axis: `right` from a hint that is not parallel to it.
void pinholeBasis(const Eigen::Vector3d& axis, Eigen::Vector3d* right, Eigen::Vector3d* vertical) {
  const Eigen::Vector3d hint =
      std::fabs(axis.z()) < 0.9 ? Eigen::Vector3d(0, 0, 1) : Eigen::Vector3d(0, 1, 0);
  *right = hint.cross(axis).normalized();
  *vertical = axis.cross(*right);
}

Eigen::Vector3d sensorAxis(int k) {
  Eigen::Vector3d axis = Eigen::Vector3d::Zero();
  axis[k / 2] = k % 2 ? -1.0 : 1.0;
  return axis;
}

SensorAxisTable makeSensorAxisTable() {
  SensorAxisTable t;
  for (int k = 0; k < 6; ++k) {
    t.along[k] = k / 2;
    t.sign[k] = k % 2 ? -1.0 : 1.0;
    Eigen::Vector3d right, vertical;
    pinholeBasis(sensorAxis(k), &right, &vertical);
    right.cwiseAbs().maxCoeff(&t.across_h[k]);
    vertical.cwiseAbs().maxCoeff(&t.across_v[k]);
  }
  return t;
}

/// The fit around any axis: a second pass over the points (the same tests and maxima as
/// addAutoSensorPoint() around a sensor axis).
AutoAxisFit fitAround(const PointCloud& cloud, const Eigen::Vector3d& axis,
                      const Eigen::Vector3d& right, const Eigen::Vector3d& vertical) {
  double tan_h = 0.0, tan_v = 0.0;
  bool fits = true;
  const long n = static_cast<long>(cloud.points_S.size());
#pragma omp parallel for schedule(static) reduction(max : tan_h, tan_v) reduction(&& : fits)
  for (long i = 0; i < n; ++i) {
    const Eigen::Vector3f& p = cloud.points_S[i];
    if (!fits || !(p.allFinite() && p.squaredNorm() > 0.f)) continue;
    const Eigen::Vector3d d = p.cast<double>();
    const double z = d.dot(axis);
    if (z <= kAutoMinForward * d.norm()) {
      fits = false;
      continue;
    }
    tan_h = std::max(tan_h, std::fabs(d.dot(right)) / z);
    tan_v = std::max(tan_v, std::fabs(d.dot(vertical)) / z);
  }
  AutoAxisFit f;
  f.tan_h = tan_h;
  f.tan_v = tan_v;
  if (!fits) f.fail();
  return f;
}
}  // namespace

const SensorAxisTable& sensorAxisTable() {
  static const SensorAxisTable table = makeSensorAxisTable();
  return table;
}

AutoSensorStats gatherAutoSensorStats(const PointCloud& cloud) {
  // In parallel over a fixed number of chunks, each gathered on its thread's stack (no cache
  // line shared with another chunk's), merged in chunk order; the merge is exact in any order.
  constexpr int kChunks = 64;
  AutoSensorStats part[kChunks];
  const size_t n = cloud.points_S.size();
#pragma omp parallel for schedule(static)
  for (int c = 0; c < kChunks; ++c) {
    // Copies on the stack: the compiler then knows the stores into q cannot change them.
    const SensorAxisTable axes = sensorAxisTable();
    AutoSensorStats q;
    for (size_t i = n * c / kChunks; i < n * (c + 1) / kChunks; ++i) {
      const Eigen::Vector3f& p = cloud.points_S[i];
      addAutoSensorPoint(p.x(), p.y(), p.z(), axes, q);
    }
    part[c] = q;
  }
  AutoSensorStats all;
  for (const AutoSensorStats& q : part) all.merge(q);
  return all;
}

SensorModel resolveAutoSensor(const SensorModel& model, const PointCloud& cloud) {
  return resolveAutoSensor(model, cloud, gatherAutoSensorStats(cloud));
}

SensorModel resolveAutoSensor(const SensorModel& model, const PointCloud& cloud,
                              const AutoSensorStats& stats) {
  // The angles come from the extreme ratios (atan and asin are monotonic).
  SensorModel out = model;
  if (out.max_range_m <= 0.0) out.max_range_m = std::max(1.0, std::ceil(stats.max_dist_m));
  if (stats.valid == 0) {  // nothing to see: a lidar model keeps culling well defined
    out.type = SensorType::kSpinningLidar;
    out.elevation_min_rad = -M_PI / 2;
    out.elevation_max_rad = M_PI / 2;
    return out;
  }
  // A pinhole pyramid when every point lies well in front of the sensor; otherwise (the points
  // surround it, or the pyramid would be too wide) a LiDAR shell. The pyramid is around the
  // sensor axis within kSnapDeg of the points' mean direction when they all fit in one around
  // it (those fits come with the first pass): a cloud in a camera's own frame keeps the
  // camera's axis, and so the same frustum scan to scan, even where invalid pixels (sky, no
  // return within range) pull the mean aside by several degrees. Else it is around the mean
  // direction (a second pass over the points).
  const auto pinhole = [&out](const Eigen::Vector3d& axis, const AutoAxisFit& fit) {
    // One degree of slack, rounded up to whole degrees.
    const double hfov = ceilDeg(2 * std::atan(fit.tan_h) + 2 * kDeg);
    const double vfov = ceilDeg(2 * std::atan(fit.tan_v) + 2 * kDeg);
    if (!fit.fits || hfov >= 170 * kDeg || vfov >= 170 * kDeg) return false;
    Eigen::Vector3d right, vertical;
    pinholeBasis(axis, &right, &vertical);
    out.type = SensorType::kPinhole;
    out.hfov_rad = hfov;
    out.vfov_rad = vfov;
    out.forward_S = axis;
    out.right_S = right;
    return true;
  };
  Eigen::Vector3d axis;
  for (int a = 0; a < 3; ++a)
    axis[a] = double(stats.dir_sum_fx[a]) / kAutoDirFixedScale / double(stats.valid);
  if (axis.norm() > 0.3) {
    axis.normalize();
    for (int k = 0; k < 6; ++k)
      if (axis.dot(sensorAxis(k)) > std::cos(kSnapDeg * kDeg) &&
          pinhole(sensorAxis(k), stats.fit[k]))
        return out;
    Eigen::Vector3d right, vertical;
    pinholeBasis(axis, &right, &vertical);
    if (pinhole(axis, fitAround(cloud, axis, right, vertical))) return out;
  }
  out.type = SensorType::kSpinningLidar;
  out.elevation_min_rad = std::max(-M_PI / 2, floorDeg(std::asin(stats.sin_min) - kDeg));
  out.elevation_max_rad = std::min(M_PI / 2, ceilDeg(std::asin(stats.sin_max) + kDeg));
  return out;
}

}  // namespace fragg
