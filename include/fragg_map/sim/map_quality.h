// Map quality against the ground-truth scene (`fragg_map eval`). With res the voxel edge and
// d = sqrt(3) / 2 * res (half a voxel diagonal):
//  * precision  = occupied voxels whose centre is within d of the scene surface / occupied voxels
//  * recall     = surface voxels (voxels whose cube the surface passes through) in the observed
//                 region that are occupied / surface voxels in the observed region; a voxel is in
//                 the observed region when it or one of its 26 neighbours is known (observed)
//  * free error = free voxels whose centre is inside a solid / free voxels; "deep" counts only
//                 those farther than d from the surface (not a discretisation effect)
// Cell states follow the map's own rule (unknown band), or OctoMap's (observed: occupied iff
// p >= 0.5) with octomap_threshold.
#pragma once

#include <cstdint>

#include "fragg_map/geometry/mesh_bvh.h"
#include "fragg_map/map.h"

namespace fragg::sim {

struct MapQualityOptions {
  bool octomap_threshold = false;
};

struct MapQuality {
  double resolution_m = 0;
  uint64_t occupied = 0;
  uint64_t occupied_near_surface = 0;
  uint64_t surface_observed = 0;           ///< surface voxels in the observed region
  uint64_t surface_observed_occupied = 0;  ///< ... that are occupied
  uint64_t surface_known = 0;              ///< surface voxels that are known themselves
  uint64_t free = 0;
  uint64_t free_inside = 0;
  uint64_t free_inside_deep = 0;

  double precision() const { return occupied ? double(occupied_near_surface) / occupied : 0.0; }
  double recall() const {
    return surface_observed ? double(surface_observed_occupied) / surface_observed : 0.0;
  }
  double knownSurfaceRecall() const {
    return surface_known ? double(surface_observed_occupied) / surface_known : 0.0;
  }
  double freeError() const { return free ? double(free_inside) / free : 0.0; }
  double freeErrorDeep() const { return free ? double(free_inside_deep) / free : 0.0; }
};

/// Evaluates `map` against the scene (map frame = scene frame). Multithreaded (OpenMP).
MapQuality evaluateMapQuality(const Map& map, const geometry::MeshBvh& scene,
                              const MapQualityOptions& options = {});

}  // namespace fragg::sim
