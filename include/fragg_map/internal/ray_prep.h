// Turning one sensor-frame point into a ray in voxel units: shared by the CPU scan preparation
// and the CUDA prepare kernel, so that both backends build the same rays bit for bit. Double
// precision, every operation spelled out (no contraction: see cmake/compile_flags.cmake).
#pragma once

#include <cmath>
#include <cstdint>

#include "fragg_map/frustum.h"
#include "fragg_map/hd.h"

namespace fragg {

struct RayEnd {
  float end_v[3];  ///< relative to the scan's reference voxel, voxel units
  uint32_t hit;    ///< 1: the end cell is a hit; 0: free-only ray (clipped or no return)
};
static_assert(sizeof(RayEnd) == 16, "RayEnd is 16 bytes");

/// Keys must stay inside int32 with room for a ray's traversal.
constexpr double kMaxAbsVoxel = 2147483647.0 - 1048576.0;

/// What one scan's rays need to know about the pose and the sensor (plain data).
struct RayPrepParams {
  double R[9];         ///< rotation map <- sensor, row-major
  double origin_m[3];  ///< sensor origin in the map frame
  double inv_res;      ///< 1 / resolution
  double ref_v[3];     ///< reference voxel (the sensor origin's), as doubles
  double min_range_m;
  double max_range_m;   ///< > 0
  bool explicit_model;  ///< drop points outside `frustum`
  float slack_m;        ///< tolerance of that test
};

enum class RayPrep : uint8_t { kHit, kFreeOnly, kInvalid, kTooClose, kOutside };

FRAGG_HD bool finiteFloat(float v) { return v - v == 0.f; }  // false for NaN and +-Inf

/// Builds the ray (map frame, relative to ref, voxel units) of the ray with sensor-frame
/// direction and length `rel_S` already clipped; false when it leaves the key range.
FRAGG_HD bool rayEndFromSensor(const RayPrepParams& p, const double s[3], bool hit, RayEnd* ray) {
  for (int a = 0; a < 3; ++a) {
    const double rel = p.R[3 * a] * s[0] + p.R[3 * a + 1] * s[1] + p.R[3 * a + 2] * s[2];
    const double end_v = (p.origin_m[a] + rel) * p.inv_res;
    if (fabs(end_v) > kMaxAbsVoxel) return false;
    ray->end_v[a] = static_cast<float>(end_v - p.ref_v[a]);
  }
  ray->hit = hit ? 1u : 0u;
  return true;
}

/// OctoMap semantics: NaN/Inf and (0,0,0) points are invalid, points closer than min range
/// dropped, points beyond max range become free-only rays ending at max range.
FRAGG_HD RayPrep prepareRay(const RayPrepParams& p, const Frustum& f, float x_S, float y_S,
                            float z_S, RayEnd* ray) {
  if (!finiteFloat(x_S) || !finiteFloat(y_S) || !finiteFloat(z_S)) return RayPrep::kInvalid;
  double s[3] = {x_S, y_S, z_S};
  const double range = sqrt(s[0] * s[0] + s[1] * s[1] + s[2] * s[2]);
  if (range == 0.0) return RayPrep::kInvalid;  // a common "no return" marker
  if (range < p.min_range_m) return RayPrep::kTooClose;
  const bool clipped = range > p.max_range_m;
  if (clipped) {
    const double k = p.max_range_m / range;
    for (double& v : s) v = v * k;
  }
  if (p.explicit_model) {
    float rel_f[3];
    for (int a = 0; a < 3; ++a)
      rel_f[a] =
          static_cast<float>(p.R[3 * a] * s[0] + p.R[3 * a + 1] * s[1] + p.R[3 * a + 2] * s[2]);
    if (!frustumContains(f, rel_f, p.slack_m)) return RayPrep::kOutside;
  }
  if (!rayEndFromSensor(p, s, !clipped, ray)) return RayPrep::kInvalid;
  return clipped ? RayPrep::kFreeOnly : RayPrep::kHit;
}

}  // namespace fragg
