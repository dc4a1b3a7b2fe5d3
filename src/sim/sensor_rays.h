// Ray casting shared by the simulated sensors (private to src/sim): the nearer of the static
// scene's and the movers' hits.
#pragma once

#include "fragg_map/geometry/mesh_bvh.h"

namespace fragg::sim {

/// The first hit of the ray within t_max_m in `scene` or `movers` (null or empty: none);
/// `dynamic` says whether it is a mover's. False when neither is hit.
inline bool nearestHit(const geometry::MeshBvh& scene, const geometry::MeshBvh* movers,
                       const Eigen::Vector3f& origin, const Eigen::Vector3f& dir_unit,
                       float t_max_m, geometry::RayHit* hit, bool* dynamic) {
  const bool hit_static = scene.intersect(origin, dir_unit, t_max_m, hit);
  *dynamic = false;
  if (movers && !movers->mesh().empty()) {
    geometry::RayHit mover_hit;
    const float limit = hit_static ? hit->t_m : t_max_m;
    if (movers->intersect(origin, dir_unit, limit, &mover_hit) &&
        (!hit_static || mover_hit.t_m < hit->t_m)) {
      *hit = mover_hit;
      *dynamic = true;
      return true;
    }
  }
  return hit_static;
}

}  // namespace fragg::sim
