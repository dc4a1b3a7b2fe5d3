// OctoMap's own ray arithmetic (RayCast::kOctomap), shared by the CPU and CUDA backends: the
// walk of liboctomap's OcTreeBaseImpl::computeRayKeys (1.9.x) step for step, so that a map
// built this way names the cells OctoMap and octomap_server name, at any range. The ray comes
// in float metres in the map frame (OctoMap's point3d); keys are floor(coordinate / resolution)
// computed in double as coordToKey does (our keys are OctoMap's minus its tree_max_val, which
// no floor changes). Float where OctoMap uses float (the direction, its length), double where
// it uses double (the boundary parameters, accumulated step by step). Coordinates keep float's
// precision in metres, so this walk is exact only as far from the origin as OctoMap's map
// reaches (+-32,768 cells); RayCast::kDda keeps full precision anywhere on an int32 map.
#pragma once

#include <cfloat>
#include <cmath>

#include "fragg_map/hd.h"
#include "fragg_map/key.h"
#include "fragg_map/raycast.h"

namespace fragg {

/// One ray as computeRayKeys sees it.
struct RayMetres {
  float origin_m[3];  ///< sensor origin, map frame, metres (as float as OctoMap keeps it)
  float end_m[3];     ///< the ray's end, map frame, metres
  double resolution_m;
  double inv_res;  ///< 1.0 / resolution_m (OctoMap's resolution_factor)
  bool end_is_hit;
  /// Clearing margin of a hit, voxels: free cells whose exit lies closer than this to the
  /// end (along the ray) are not visited (RayVox::keep_v).
  float keep_v = 0.f;
  /// A free-only ray whose end cell is visited as free too (RayVox::end_is_free).
  bool end_is_free = false;
};

/// OctoMap's coordToKey on one axis, without its offset (tree_max_val).
FRAGG_HD int octomapKey(float coord_m, double inv_res) {
  return static_cast<int>(floor(inv_res * static_cast<double>(coord_m)));
}

/// The entry code (raycast.h) of cell `cur` after the visited cell `prev`.
FRAGG_HD int entryAfter(const VoxelKey& prev, const VoxelKey& cur) {
  const BlockKey a = blockKeyOf(prev), b = blockKeyOf(cur);
  const int dx = b.x - a.x, dy = b.y - a.y, dz = b.z - a.z;
  if (dx == 0 && dy == 0 && dz == 0) return kSameBlock;
  if (dy == 0 && dz == 0 && (dx == 1 || dx == -1)) return blockFace(0, dx);
  if (dx == 0 && dz == 0 && (dy == 1 || dy == -1)) return blockFace(1, dy);
  if (dx == 0 && dy == 0 && (dz == 1 || dz == -1)) return blockFace(2, dz);
  return kUnknownBlock;
}

/// Walks the ray as computeRayKeys does and calls `visit(key, is_hit, entry)` as traverseDda
/// does: the free cells from the origin's cell on (computeRayKeys's key ray), then the end
/// cell (a hit, or free with `end_is_free`). The walk stops at the end cell's key, or when the
/// next boundary lies beyond the ray's length (OctoMap's guard against rounding), so the end
/// cell may not be reached; it is visited all the same, as insertPointCloud marks it. A
/// visitor with `skippingBlock()` (CanSkipBlock) skips the rest of the block after a free
/// visit: the walk goes on without visiting until it enters another block. Returns how many
/// cells it visited.
template <class Visit>
FRAGG_HD int traverseOctomapKeys(const RayMetres& ray, Visit& visit) {
  const double res = ray.resolution_m;
  const VoxelKey key_o{octomapKey(ray.origin_m[0], ray.inv_res),
                       octomapKey(ray.origin_m[1], ray.inv_res),
                       octomapKey(ray.origin_m[2], ray.inv_res)};
  const VoxelKey key_e{octomapKey(ray.end_m[0], ray.inv_res), octomapKey(ray.end_m[1], ray.inv_res),
                       octomapKey(ray.end_m[2], ray.inv_res)};
  int visited = 0;
  VoxelKey prev{};
  const auto visitCell = [&](const VoxelKey& k, bool is_hit) {
    visit(k, is_hit, visited > 0 ? entryAfter(prev, k) : kUnknownBlock);
    prev = k;
    ++visited;
  };
  if (key_o != key_e) {
    // Initialisation, as computeRayKeys: float direction and length, double parameters.
    const float d0 = ray.end_m[0] - ray.origin_m[0];
    const float d1 = ray.end_m[1] - ray.origin_m[1];
    const float d2 = ray.end_m[2] - ray.origin_m[2];
    const float dd0 = d0 * d0, dd1 = d1 * d1, dd2 = d2 * d2;  // no contraction: same bits
    const float sum = dd0 + dd1 + dd2;
    const float length = static_cast<float>(sqrt(static_cast<double>(sum)));
    const float dir[3] = {d0 / length, d1 / length, d2 / length};
    const int o[3] = {key_o.x, key_o.y, key_o.z};
    int step[3];
    double t_max[3], t_delta[3];
    for (int i = 0; i < 3; ++i) {
      step[i] = dir[i] > 0.f ? 1 : (dir[i] < 0.f ? -1 : 0);
      if (step[i] != 0) {
        double border = (static_cast<double>(o[i]) + 0.5) * res;  // keyToCoord
        const double half = static_cast<double>(step[i]) * res * 0.5;
        border += static_cast<double>(static_cast<float>(half));
        t_max[i] = (border - static_cast<double>(ray.origin_m[i])) / static_cast<double>(dir[i]);
        t_delta[i] = res / static_cast<double>(fabsf(dir[i]));
      } else {
        t_max[i] = DBL_MAX;
        t_delta[i] = DBL_MAX;
      }
    }
    // The clearing margin as a distance along the ray (metres): a free cell whose exit lies
    // beyond `keep_after` is inside it.
    const bool has_margin = ray.end_is_hit && ray.keep_v > 0.f;
    const double keep_after = static_cast<double>(length) - static_cast<double>(ray.keep_v) * res;
    const double length_d = static_cast<double>(length);
    // A walk takes about as many steps as the keys differ; the cap only guards against a
    // non-finite ray (computeRayKeys has none: it asserts).
    const int span =
        absInt(key_e.x - key_o.x) + absInt(key_e.y - key_o.y) + absInt(key_e.z - key_o.z);
    const int max_steps = 2 * span + 64;
    int cur[3] = {o[0], o[1], o[2]};
    bool skipping = false;
    BlockKey skip_block{};
    for (int n = 0;; ++n) {
      // The current cell is free (the origin's cell first, as computeRayKeys adds it).
      const VoxelKey key{cur[0], cur[1], cur[2]};
      if (skipping && blockKeyOf(key) != skip_block) skipping = false;
      const double exit_t = fmin(fmin(t_max[0], t_max[1]), t_max[2]);
      if (!skipping && !(has_margin && exit_t > keep_after)) {
        visitCell(key, false);
        if constexpr (CanSkipBlock<Visit>::value) {
          if (visit.skippingBlock()) {
            skipping = true;
            skip_block = blockKeyOf(key);
          }
        }
      }
      if (n >= max_steps) break;
      const int dim =
          t_max[0] < t_max[1] ? (t_max[0] < t_max[2] ? 0 : 2) : (t_max[1] < t_max[2] ? 1 : 2);
      cur[dim] += step[dim];
      t_max[dim] += t_delta[dim];
      if (cur[0] == key_e.x && cur[1] == key_e.y && cur[2] == key_e.z) break;
      if (fmin(fmin(t_max[0], t_max[1]), t_max[2]) > length_d) break;
    }
  }
  if (ray.end_is_hit || ray.end_is_free) visitCell(key_e, ray.end_is_hit);
  return visited;
}

}  // namespace fragg
