// What an `auto` sensor model is resolved from (resolveAutoSensor): one pass over a cloud's
// points gathers these statistics, on the host or on the device (CUDA backend), with the same
// bits either way: the maxima and minima are exact in any order, the direction sum is kept in
// fixed point (integer sums do not depend on the order), and the per-point arithmetic below
// is shared (no contraction: the project compiles with -ffp-contract=off / --fmad=false).
#pragma once

#include <cmath>
#include <cstdint>

#include "fragg_map/hd.h"

namespace fragg {

/// Unit directions are summed as integers of 2^-32 (each component truncated): up to 2^31
/// points cannot overflow.
constexpr double kAutoDirFixedScale = 4294967296.0;
/// A point must lie in front of a pinhole axis by more than this fraction of its range
/// (cos 85 degrees): a wider cloud is a LiDAR's.
constexpr double kAutoMinForward = 0.087155742747658166;

/// The six sensor axes (+x, -x, +y, -y, +z, -z) to which a camera cloud's axis snaps, and the
/// coordinates of their pinhole bases: for axis k, the coordinate along it is `along[k]` (times
/// `sign[k]`), across `right` it is `across_h[k]`, across `vertical` `across_v[k]` (the bases
/// are sensor axes too, so a point's dot products with them are single coordinates, exactly).
struct SensorAxisTable {
  int along[6], across_h[6], across_v[6];
  double sign[6];
};

/// The pinhole fit of a cloud around one axis: every valid point in front of it and the
/// largest tangents across its right and vertical axes. An axis that does not fit has both
/// tangents 0 (what was gathered before the point that failed it would depend on the order).
struct AutoAxisFit {
  int32_t fits = 1;
  double tan_h = 0.0, tan_v = 0.0;
  FRAGG_HD void fail() {
    fits = 0;
    tan_h = tan_v = 0.0;
  }
  FRAGG_HD void merge(const AutoAxisFit& o) {
    if (!fits || !o.fits) {
      fail();
      return;
    }
    tan_h = tan_h < o.tan_h ? o.tan_h : tan_h;
    tan_v = tan_v < o.tan_v ? o.tan_v : tan_v;
  }
};

struct AutoSensorStats {
  double max_dist_m = 0.0;               ///< farthest valid point
  double sin_min = 1.0, sin_max = -1.0;  ///< elevation sines (z / range), -0 read as +0
  int64_t dir_sum_fx[3] = {0, 0, 0};     ///< sum of unit directions, x kAutoDirFixedScale
  uint64_t valid = 0;                    ///< finite points other than the origin
  AutoAxisFit fit[6];                    ///< around the six sensor axes (SensorAxisTable)

  FRAGG_HD void merge(const AutoSensorStats& o) {
    max_dist_m = max_dist_m < o.max_dist_m ? o.max_dist_m : max_dist_m;
    sin_min = o.sin_min < sin_min ? o.sin_min : sin_min;
    sin_max = sin_max < o.sin_max ? o.sin_max : sin_max;
    for (int a = 0; a < 3; ++a) dir_sum_fx[a] += o.dir_sum_fx[a];
    valid += o.valid;
    for (int k = 0; k < 6; ++k) fit[k].merge(o.fit[k]);
  }
};

/// max(tan, across / z) for z > 0, dividing only when the ratio may exceed `tan`: a ratio
/// whose rounded quotient is above `tan` is above it exactly, so across > tan * z, and the
/// product's rounding (half an ulp) stays far inside the 1e-12 slack. The same maximum as
/// dividing every time, to the bit, in any order.
FRAGG_HD double raiseAutoTangent(double tan, double across, double z) {
  if (across < tan * z * (1.0 - 1e-12)) return tan;
  const double q = across / z;
  return tan < q ? q : tan;
}

/// One point (sensor frame, metres) into `s`; invalid points (not finite, or the origin) are
/// left out.
FRAGG_HD void addAutoSensorPoint(float px, float py, float pz, const SensorAxisTable& axes,
                                 AutoSensorStats& s) {
  if (!(px - px == 0.f && py - py == 0.f && pz - pz == 0.f)) return;  // NaN or +-Inf
  if (!((px * px + py * py) + pz * pz > 0.f)) return;
  const double d[3] = {px, py, pz};
  const double r = sqrt((d[0] * d[0] + d[1] * d[1]) + d[2] * d[2]);
  const double inv_r = 1.0 / r;
  s.max_dist_m = s.max_dist_m < r ? r : s.max_dist_m;
  // Truncated to an integer (toward zero, as C++ and CUDA convert): the same bits on host and
  // device, one instruction. Scaling inv_r by a power of two first is exact, so each term is
  // the unit direction's component x 2^32 (|term| <= 2^32), truncated.
  const double inv_r_fx = inv_r * kAutoDirFixedScale;
  for (int a = 0; a < 3; ++a) s.dir_sum_fx[a] += static_cast<int64_t>(d[a] * inv_r_fx);
  double sn = d[2] * inv_r;
  sn = (sn < -1.0 ? -1.0 : (sn > 1.0 ? 1.0 : sn)) + 0.0;  // + 0.0: -0 becomes +0
  s.sin_min = sn < s.sin_min ? sn : s.sin_min;
  s.sin_max = s.sin_max < sn ? sn : s.sin_max;
  ++s.valid;
  const double forward_min = kAutoMinForward * r;
  for (int k = 0; k < 6; ++k) {
    AutoAxisFit& f = s.fit[k];
    if (!f.fits) continue;
    const double z = axes.sign[k] * d[axes.along[k]];
    if (z <= forward_min) {
      f.fail();
      continue;
    }
    f.tan_h = raiseAutoTangent(f.tan_h, fabs(d[axes.across_h[k]]), z);
    f.tan_v = raiseAutoTangent(f.tan_v, fabs(d[axes.across_v[k]]), z);
  }
}

}  // namespace fragg
