// The region a sensor sees at one pose, in the map frame, as a short list of tests. Each test
// returns a margin: > 0 means the tested box lies outside by at least that many metres.
// Margins are true distance bounds, so a rejection stays valid while the sensor moves less
// than the margin; culling.h builds its coherence rules on that.
//
// Coordinates are relative to the sensor origin (metres, float), so precision does not depend
// on how far from the map origin the robot is.
#pragma once

#include <cmath>
#include <cstdint>

#include "fragg_map/hd.h"
#include "fragg_map/key.h"

namespace fragg {

enum class FrustumTest : uint8_t {
  kPlane = 0,     ///< inside: n . x + d >= 0
  kRangeSphere,   ///< inside: |x| <= max_range
  kElevationMax,  ///< inside: elevation about `up` <= elevation_max
  kElevationMin,  ///< inside: elevation about `up` >= elevation_min
};

constexpr int kMaxFrustumTests = 8;
/// Index of the near plane in a pinhole frustum (the one translation coherence applies to).
constexpr int kNearPlaneTest = 0;

struct Frustum {
  double origin_m[3] = {0, 0, 0};  ///< sensor origin in the map frame
  int num_tests = 0;
  FrustumTest tests[kMaxFrustumTests] = {};
  float planes[kMaxFrustumTests][4] = {};  ///< unit inward normal + offset, for kPlane tests
  float up[3] = {0, 0, 1};                 ///< LiDAR spin axis (map frame)
  float max_range_m = 0.f;
  float elevation_min_rad = 0.f;
  float elevation_max_rad = 0.f;
  bool is_pinhole = false;
  BlockKey aabb_min;  ///< blocks that may intersect the frustum (inclusive)
  BlockKey aabb_max;
};

FRAGG_HD float dot3(const float a[3], const float b[3]) {
  return a[0] * b[0] + a[1] * b[1] + a[2] * b[2];
}

/// Margin of test `i` for a box with centre `c` (relative to the sensor origin, metres) and
/// half edge `h`; > 0 means the whole box is outside.
FRAGG_HD float frustumTestMargin(const Frustum& f, int i, const float c[3], float h) {
  const float kSqrt3 = 1.7320508f;
  switch (f.tests[i]) {
    case FrustumTest::kPlane: {
      const float* p = f.planes[i];
      const float reach = h * (fabsf(p[0]) + fabsf(p[1]) + fabsf(p[2]));
      return -(p[0] * c[0] + p[1] * c[1] + p[2] * c[2] + p[3]) - reach;
    }
    case FrustumTest::kRangeSphere:
      return sqrtf(dot3(c, c)) - h * kSqrt3 - f.max_range_m;
    case FrustumTest::kElevationMax:
    case FrustumTest::kElevationMin: {
      const float r = sqrtf(dot3(c, c));
      if (r <= h * kSqrt3) return -1.f;
      const float z = dot3(c, f.up);
      const float horizontal = sqrtf(fmaxf(r * r - z * z, 0.f));
      const float elevation = atan2f(z, horizontal);
      const float delta = f.tests[i] == FrustumTest::kElevationMax
                              ? elevation - f.elevation_max_rad
                              : f.elevation_min_rad - elevation;
      if (delta <= 0.f) return delta;  // centre inside: negative, never rejects
      // Distance from the centre to the cone surface, in the meridian plane.
      const float dist = delta >= 1.5707963f ? r : r * sinf(delta);
      return dist - h * kSqrt3;
    }
  }
  return -1.f;
}

/// True when point `p` (relative to the sensor origin, metres) passes every test, with a
/// tolerance of `slack_m`.
FRAGG_HD bool frustumContains(const Frustum& f, const float p[3], float slack_m) {
  for (int i = 0; i < f.num_tests; ++i)
    if (frustumTestMargin(f, i, p, 0.f) > slack_m) return false;
  return true;
}

}  // namespace fragg
