// Turning one sensor-frame point into a ray in voxel units: shared by the CPU scan preparation
// and the CUDA prepare kernel, so that both backends build the same rays bit for bit. Double
// precision, every operation spelled out (no contraction: see cmake/compile_flags.cmake).
#pragma once

#include <cmath>
#include <cstdint>

#include "fragg_map/frustum.h"
#include "fragg_map/hd.h"
#include "fragg_map/raycast_octomap.h"

namespace fragg {

struct RayEnd {
  /// Relative to the scan's reference voxel, voxel units; with RayCast::kOctomap the end in
  /// float metres in the map frame instead (rayEndCell reads either).
  float end_v[3];
  /// 0: free-only ray (clipped or no return); kFreeEndCode: a ray cut at max range whose end
  /// cell is free too (MapParams::free_cut_cell); otherwise the end cell is a hit and
  /// (hit - 1) / kMarginSteps is its clearing margin in voxels (see RayVox::keep_v).
  uint32_t hit;
};
static_assert(sizeof(RayEnd) == 16, "RayEnd is 16 bytes");

/// Clearing margins are kept in 1/256 voxel, up to kMaxMarginV voxels.
constexpr float kMarginSteps = 256.f;
constexpr double kMaxMarginV = 65536.0;

/// RayEnd::hit of a ray cut at max range whose end cell is free as well (octomap_server's
/// rule). Above every hit code (at most 1 + kMaxMarginV * kMarginSteps) and, read as the float
/// of a float4 on the device, a finite number.
constexpr uint32_t kFreeEndCode = 0x7F000000u;

/// True when a RayEnd::hit value makes the end cell a hit.
FRAGG_HD bool isHitCode(uint32_t hit) { return hit != 0u && hit != kFreeEndCode; }

/// RayEnd::hit of a hit whose clearing margin is `margin_v` voxels (>= 0).
FRAGG_HD uint32_t hitCode(double margin_v) {
  const double m = margin_v < kMaxMarginV ? margin_v : kMaxMarginV;
  return 1u + static_cast<uint32_t>(floor(m * kMarginSteps + 0.5));
}
/// The clearing margin (voxels) of a RayEnd::hit value; 0 for a free-only ray.
FRAGG_HD float marginOfHitCode(uint32_t hit) {
  return isHitCode(hit) ? static_cast<float>(hit - 1u) / kMarginSteps : 0.f;
}

/// Keys must stay inside int32 with room for a ray's traversal.
constexpr double kMaxAbsVoxel = 2147483647.0 - 1048576.0;
/// The farthest a ray's end may lie from the scan's reference voxel on any axis, voxels (2^24:
/// beyond it consecutive floats are two voxels apart, so the float traversal could name
/// neither the end cell nor every cell on the way; 839 km at 5 cm). Such a point is dropped
/// and counted as invalid, as one beyond the key range is.
constexpr double kMaxRayV = 16777216.0;

/// What one scan's rays need to know about the pose and the sensor (plain data).
struct RayPrepParams {
  double R[9];         ///< rotation map <- sensor, row-major
  double origin_m[3];  ///< sensor origin in the map frame
  double inv_res;      ///< 1 / resolution
  double ref_v[3];     ///< reference voxel (the sensor origin's), as doubles
  double min_range_m;
  double max_range_m;  ///< > 0
  /// Range noise of the sensor: sigma(r) = noise_m + noise_quadratic_per_m * r^2; a hit's
  /// clearing margin is sigma(r) at its measured range.
  double noise_m;
  double noise_quadratic_per_m;
  bool explicit_model;  ///< drop points outside `frustum`
  float slack_m;        ///< tolerance of that test
  /// A ray cut at max range also frees the cell at the cut point (octomap_server's rule; off:
  /// liboctomap's insertPointCloud, that cell is left as it was).
  bool free_cut_cell;
  /// RayCast::kOctomap: rays end in float metres, cut at max range in float as OctoMap cuts
  /// them (octomapRayEnd).
  bool octomap_keys = false;
  float origin_f[3] = {0.f, 0.f, 0.f};  ///< origin_m as float (OctoMap's point3d)
};

enum class RayPrep : uint8_t { kHit, kFreeOnly, kInvalid, kTooClose, kOutside };

FRAGG_HD bool finiteFloat(float v) { return v - v == 0.f; }  // false for NaN and +-Inf

/// Builds the ray (map frame, relative to ref, voxel units) of the ray with sensor-frame
/// direction and length `s` already clipped, `hit` as in RayEnd::hit; false when it leaves
/// the key range or ends farther than kMaxRayV from the reference voxel (or is not finite).
FRAGG_HD bool rayEndFromSensor(const RayPrepParams& p, const double s[3], uint32_t hit,
                               RayEnd* ray) {
  for (int a = 0; a < 3; ++a) {
    const double rel = p.R[3 * a] * s[0] + p.R[3 * a + 1] * s[1] + p.R[3 * a + 2] * s[2];
    const double end_v = (p.origin_m[a] + rel) * p.inv_res;
    if (!(fabs(end_v) <= kMaxAbsVoxel)) return false;
    const double rel_v = end_v - p.ref_v[a];
    if (!(fabs(rel_v) <= kMaxRayV)) return false;
    ray->end_v[a] = static_cast<float>(rel_v);
  }
  ray->hit = hit;
  return true;
}

/// The end cell of a ray on axis `a`, relative to the reference voxel `ref_a`.
FRAGG_HD int rayEndCell(const RayEnd& r, int a, bool octomap_keys, double inv_res, int ref_a) {
  return octomap_keys ? octomapKey(r.end_v[a], inv_res) - ref_a : floorToInt(r.end_v[a]);
}

/// RayCast::kOctomap's end of the ray with sensor-frame direction and length `s` (not cut):
/// the point in float metres in the map frame, cut at max range as liboctomap's
/// insertPointCloud and octomap_server cut it (float difference, its norm in double, the
/// normalised direction times the float max range). Sets `clipped`; false when the end
/// leaves the key range or lies farther than kMaxRayV from the reference voxel.
FRAGG_HD bool octomapRayEnd(const RayPrepParams& p, const double s[3], bool* clipped,
                            float end_m[3]) {
  float d[3];
  for (int a = 0; a < 3; ++a) {
    const double rel = p.R[3 * a] * s[0] + p.R[3 * a + 1] * s[1] + p.R[3 * a + 2] * s[2];
    end_m[a] = static_cast<float>(p.origin_m[a] + rel);
    d[a] = end_m[a] - p.origin_f[a];
  }
  const float dd0 = d[0] * d[0], dd1 = d[1] * d[1], dd2 = d[2] * d[2];  // no contraction
  const double norm = sqrt(static_cast<double>(dd0 + dd1 + dd2));
  *clipped = norm > p.max_range_m;
  if (*clipped) {
    const float len = static_cast<float>(norm), max_range = static_cast<float>(p.max_range_m);
    for (int a = 0; a < 3; ++a) {
      const float dir = d[a] / len;
      const float reach = dir * max_range;
      end_m[a] = p.origin_f[a] + reach;
    }
  }
  for (int a = 0; a < 3; ++a) {
    if (!finiteFloat(end_m[a])) return false;
    const double end_v = static_cast<double>(end_m[a]) * p.inv_res;
    if (!(fabs(end_v) <= kMaxAbsVoxel)) return false;
    if (!(fabs(end_v - p.ref_v[a]) <= kMaxRayV)) return false;
  }
  return true;
}

/// A free-only ray with sensor-frame direction and length `s` (a no-return ray), in the
/// units RayEnd::end_v has for this scan; false as rayEndFromSensor / octomapRayEnd.
FRAGG_HD bool freeRayEnd(const RayPrepParams& p, const double s[3], RayEnd* ray) {
  if (!p.octomap_keys) return rayEndFromSensor(p, s, 0u, ray);
  bool clipped = false;
  if (!octomapRayEnd(p, s, &clipped, ray->end_v)) return false;
  ray->hit = 0u;
  return true;
}

/// OctoMap semantics: NaN/Inf and (0,0,0) points are invalid, points closer than min range
/// dropped, points beyond max range become free-only rays ending at max range (with
/// `free_cut_cell`, rays whose end cell is free too: kFreeEndCode). A point marked
/// `free_only` (PointCloud::free_only) gives a free-only ray ending at the point (at max range
/// when farther). A hit carries its clearing margin: the sensor's range noise at the measured
/// range, in voxels.
FRAGG_HD RayPrep prepareRay(const RayPrepParams& p, const Frustum& f, float x_S, float y_S,
                            float z_S, bool free_only, RayEnd* ray) {
  if (!finiteFloat(x_S) || !finiteFloat(y_S) || !finiteFloat(z_S)) return RayPrep::kInvalid;
  double s[3] = {x_S, y_S, z_S};
  const double range = sqrt(s[0] * s[0] + s[1] * s[1] + s[2] * s[2]);
  if (range == 0.0) return RayPrep::kInvalid;  // a common "no return" marker
  if (range < p.min_range_m) return RayPrep::kTooClose;
  float end_m[3] = {0.f, 0.f, 0.f};
  bool octomap_clipped = false;
  if (p.octomap_keys && !octomapRayEnd(p, s, &octomap_clipped, end_m)) return RayPrep::kInvalid;
  const bool clipped = p.octomap_keys ? octomap_clipped : range > p.max_range_m;
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
  const bool no_hit = clipped || free_only;
  uint32_t hit = clipped && !free_only && p.free_cut_cell ? kFreeEndCode : 0u;
  if (!no_hit) {
    const double noise_m = p.noise_m + p.noise_quadratic_per_m * range * range;
    hit = hitCode(noise_m * p.inv_res);
  }
  if (p.octomap_keys) {
    for (int a = 0; a < 3; ++a) ray->end_v[a] = end_m[a];
    ray->hit = hit;
  } else if (!rayEndFromSensor(p, s, hit, ray)) {
    return RayPrep::kInvalid;
  }
  return no_hit ? RayPrep::kFreeOnly : RayPrep::kHit;
}

}  // namespace fragg
