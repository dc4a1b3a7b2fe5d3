// Ray traversal shared by the CPU and CUDA backends.
//
// OctoMap semantics: the cells from the sensor's cell up to (not including) the endpoint cell
// are free; the endpoint cell is a hit unless the ray was clipped at max range (then it is
// neither). Coordinates come in voxel units (metres / resolution) relative to a reference
// voxel near the sensor, so float traversal keeps full precision anywhere on an int32 map.
#pragma once

#include <cmath>
#include <cstdint>

#include "fragg_map/hd.h"
#include "fragg_map/key.h"

namespace fragg {

/// One ray in voxel units: `start_v` and `end_v` are relative to `ref` (a voxel key).
struct RayVox {
  VoxelKey ref;
  float start_v[3];
  float end_v[3];
  bool end_is_hit;
};

FRAGG_HD int floorToInt(float v) { return static_cast<int>(floorf(v)); }

/// Exact 3D DDA (Amanatides & Woo). Visits every cell the segment passes through, in order,
/// 6-connected; the per-axis step counts are fixed up front, so the walk always ends in the
/// endpoint's cell. `visit(key, is_hit)` is called once per cell.
template <class Visit>
FRAGG_HD void traverseDda(const RayVox& ray, Visit& visit) {
  int cur[3], remaining[3], step[3];
  float t_max[3], t_delta[3];
  for (int a = 0; a < 3; ++a) {
    const int s = floorToInt(ray.start_v[a]);
    const int e = floorToInt(ray.end_v[a]);
    const float d = ray.end_v[a] - ray.start_v[a];
    cur[a] = s;
    if (e > s) {
      step[a] = 1;
      remaining[a] = e - s;
      t_delta[a] = 1.f / d;
      t_max[a] = (static_cast<float>(s + 1) - ray.start_v[a]) / d;
    } else if (e < s) {
      step[a] = -1;
      remaining[a] = s - e;
      t_delta[a] = -1.f / d;
      t_max[a] = (ray.start_v[a] - static_cast<float>(s)) / -d;
    } else {
      step[a] = 0;
      remaining[a] = 0;
      t_delta[a] = 0.f;
      t_max[a] = INFINITY;
    }
  }
  const VoxelKey& r = ray.ref;
  int total = remaining[0] + remaining[1] + remaining[2];
  while (total > 0) {
    visit(VoxelKey{r.x + cur[0], r.y + cur[1], r.z + cur[2]}, false);
    int a;
    if (t_max[0] < t_max[1]) {
      a = t_max[0] < t_max[2] ? 0 : 2;
    } else {
      a = t_max[1] < t_max[2] ? 1 : 2;
    }
    // An axis whose steps are used up never advances again (guards against rounding).
    if (remaining[a] == 0) {
      a = remaining[0] ? 0 : (remaining[1] ? 1 : 2);
    }
    cur[a] += step[a];
    --remaining[a];
    t_max[a] = remaining[a] ? t_max[a] + t_delta[a] : INFINITY;
    --total;
  }
  if (ray.end_is_hit) visit(VoxelKey{r.x + cur[0], r.y + cur[1], r.z + cur[2]}, true);
}

FRAGG_HD int absInt(int v) { return v < 0 ? -v : v; }

/// 3D Bresenham line between the start and end cells (26-connected, integer only).
template <class Visit>
FRAGG_HD void traverseBresenham(const RayVox& ray, Visit& visit) {
  int cur[3], d[3], s[3];
  for (int a = 0; a < 3; ++a) {
    cur[a] = floorToInt(ray.start_v[a]);
    const int e = floorToInt(ray.end_v[a]);
    d[a] = absInt(e - cur[a]);
    s[a] = e > cur[a] ? 1 : (e < cur[a] ? -1 : 0);
  }
  const int major = d[0] >= d[1] ? (d[0] >= d[2] ? 0 : 2) : (d[1] >= d[2] ? 1 : 2);
  const int a1 = (major + 1) % 3, a2 = (major + 2) % 3;
  int err1 = 2 * d[a1] - d[major];
  int err2 = 2 * d[a2] - d[major];
  const VoxelKey& r = ray.ref;
  for (int i = 0; i < d[major]; ++i) {
    visit(VoxelKey{r.x + cur[0], r.y + cur[1], r.z + cur[2]}, false);
    if (err1 > 0) {
      cur[a1] += s[a1];
      err1 -= 2 * d[major];
    }
    if (err2 > 0) {
      cur[a2] += s[a2];
      err2 -= 2 * d[major];
    }
    err1 += 2 * d[a1];
    err2 += 2 * d[a2];
    cur[major] += s[major];
  }
  if (ray.end_is_hit) visit(VoxelKey{r.x + cur[0], r.y + cur[1], r.z + cur[2]}, true);
}

}  // namespace fragg
