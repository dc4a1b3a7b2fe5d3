#include "fragg_map/internal/frustum_builder.h"

#include <algorithm>
#include <cmath>

#include "fragg_map/errors.h"

namespace fragg {

namespace {
void addPlane(Frustum& f, const Eigen::Vector3d& inward_normal) {
  const int i = f.num_tests++;
  f.tests[i] = FrustumTest::kPlane;
  const Eigen::Vector3d n = inward_normal.normalized();
  f.planes[i][0] = static_cast<float>(n.x());
  f.planes[i][1] = static_cast<float>(n.y());
  f.planes[i][2] = static_cast<float>(n.z());
  f.planes[i][3] = 0.f;  // every plane passes through the sensor origin
}

void addTest(Frustum& f, FrustumTest t) { f.tests[f.num_tests++] = t; }

/// The block holding `v_m`, clamped to the blocks of the int32 key range: an auto model's range
/// is the farthest point's, which may lie far beyond what the map can hold (such points give
/// no ray), and the box then spans the whole key range.
int32_t blockFloor(double v_m, double block_m) {
  constexpr double kLast = 2147483647.0 / kBlockSize;  // 2^28 - 1 (floored below)
  const double b = std::floor(v_m / block_m);
  return static_cast<int32_t>(std::clamp(b, -std::floor(kLast) - 1.0, std::floor(kLast)));
}
}  // namespace

Frustum buildFrustum(const SensorModel& model, const Eigen::Isometry3d& T_map_sensor,
                     double resolution_m) {
  if (model.type == SensorType::kAuto)
    throw InvalidArgument("buildFrustum needs a resolved sensor model (not auto)");
  if (!(model.max_range_m > 0.0)) throw InvalidArgument("frustum needs a max range > 0");
  Frustum f;
  const Eigen::Vector3d o = T_map_sensor.translation();
  const Eigen::Matrix3d R = T_map_sensor.linear();
  for (int a = 0; a < 3; ++a) f.origin_m[a] = o[a];
  const double D = model.max_range_m;
  f.max_range_m = static_cast<float>(D);
  Eigen::Vector3d rel_lo = Eigen::Vector3d::Constant(-D), rel_hi = Eigen::Vector3d::Constant(D);

  if (model.type == SensorType::kPinhole) {
    f.is_pinhole = true;
    const Eigen::Vector3d fwd = R * model.forward_S, right = R * model.right_S;
    const Eigen::Vector3d vert = fwd.cross(right);
    const double ha = model.hfov_rad / 2, va = model.vfov_rad / 2;
    addPlane(f, fwd);  // near plane: test kNearPlaneTest
    addPlane(f, std::sin(ha) * fwd - std::cos(ha) * right);
    addPlane(f, std::sin(ha) * fwd + std::cos(ha) * right);
    addPlane(f, std::sin(va) * fwd - std::cos(va) * vert);
    addPlane(f, std::sin(va) * fwd + std::cos(va) * vert);
    addTest(f, FrustumTest::kRangeSphere);
    // Bounding box of the pyramid cut at depth D (holds every point within range D).
    Eigen::Vector3d lo = Eigen::Vector3d::Zero(), hi = Eigen::Vector3d::Zero();
    for (double sh : {-1.0, 1.0})
      for (double sv : {-1.0, 1.0}) {
        const Eigen::Vector3d c = D * (fwd + sh * std::tan(ha) * right + sv * std::tan(va) * vert);
        lo = lo.cwiseMin(c);
        hi = hi.cwiseMax(c);
      }
    rel_lo = rel_lo.cwiseMax(lo);
    rel_hi = rel_hi.cwiseMin(hi);
  } else {
    const Eigen::Vector3d up = R.col(2);
    for (int a = 0; a < 3; ++a) f.up[a] = static_cast<float>(up[a]);
    f.elevation_min_rad = static_cast<float>(model.elevation_min_rad);
    f.elevation_max_rad = static_cast<float>(model.elevation_max_rad);
    addTest(f, FrustumTest::kRangeSphere);
    if (model.elevation_max_rad < M_PI / 2 - 1e-6) addTest(f, FrustumTest::kElevationMax);
    if (model.elevation_min_rad > -M_PI / 2 + 1e-6) addTest(f, FrustumTest::kElevationMin);
    if (std::fabs(up.z()) > 0.9999) {  // spin axis vertical: the shell's height is bounded
      // Heights along the spin axis, then in map z (the axis may point down).
      const double along_lo = std::min(0.0, D * std::sin(model.elevation_min_rad));
      const double along_hi = std::max(0.0, D * std::sin(model.elevation_max_rad));
      const double zlo = up.z() > 0 ? along_lo : -along_hi;
      const double zhi = up.z() > 0 ? along_hi : -along_lo;
      rel_lo.z() = std::max(rel_lo.z(), zlo - 1e-3 * D);
      rel_hi.z() = std::min(rel_hi.z(), zhi + 1e-3 * D);
    }
  }
  const double block_m = resolution_m * kBlockSize;
  f.aabb_min = {blockFloor(o.x() + rel_lo.x(), block_m), blockFloor(o.y() + rel_lo.y(), block_m),
                blockFloor(o.z() + rel_lo.z(), block_m)};
  f.aabb_max = {blockFloor(o.x() + rel_hi.x(), block_m), blockFloor(o.y() + rel_hi.y(), block_m),
                blockFloor(o.z() + rel_hi.z(), block_m)};
  return f;
}

}  // namespace fragg
