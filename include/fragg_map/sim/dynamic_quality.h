// How well a map leaves moving objects out (`fragg_map eval --labels`), with the metrics of the
// KTH DynamicMap benchmark (Zhang et al., arXiv 2307.07260) on labelled scans, and ghost cells
// against the static truth:
//  * SA (static accuracy)  = static points whose voxel is occupied in the map / static points
//  * DA (dynamic accuracy) = dynamic points whose voxel is not occupied / dynamic points
//  * ghost cells           = occupied voxels whose centre lies farther than d = sqrt(3)/2 * res
//                            from the static scene's surface and outside its solids (free in
//                            the static truth: what movers leave behind)
// Points are the scans' finite points in the map frame (ground-truth poses), every one counted
// (no down-sampling). Cell states follow the map's rule, or OctoMap's (occupied iff p >= 0.5)
// with octomap_threshold, as in map_quality.h.
#pragma once

#include <Eigen/Geometry>
#include <cstdint>
#include <limits>
#include <vector>

#include "fragg_map/geometry/mesh_bvh.h"
#include "fragg_map/map.h"
#include "fragg_map/point_cloud.h"

namespace fragg::sim {

struct DynamicQuality {
  uint64_t static_points = 0;
  uint64_t static_kept = 0;  ///< static points in an occupied voxel
  uint64_t dynamic_points = 0;
  uint64_t dynamic_removed = 0;  ///< dynamic points in a voxel that is not occupied
  uint64_t occupied = 0;         ///< occupied voxels of the map
  uint64_t ghost_cells = 0;      ///< occupied voxels free in the static truth

  /// SA, in [0, 1] (0 without static points).
  [[nodiscard]] double staticAccuracy() const {
    return static_points ? double(static_kept) / static_points : 0.0;
  }
  /// DA, in [0, 1] (0 without dynamic points).
  [[nodiscard]] double dynamicAccuracy() const {
    return dynamic_points ? double(dynamic_removed) / dynamic_points : 0.0;
  }
};

/// Adds one labelled scan to SA and DA: `labels` holds one flag (1 = dynamic) a finite point
/// of `cloud_S`, in order (readDynamicLabels). Throws InvalidArgument when the count differs.
/// Points farther than `max_range_m` from the sensor (> 0; the map's build range) are left out:
/// no map inserts them.
void addLabelledScan(const Map& map, const PointCloud& cloud_S,
                     const Eigen::Isometry3d& T_map_sensor, const std::vector<uint8_t>& labels,
                     bool octomap_threshold, DynamicQuality& quality,
                     double max_range_m = std::numeric_limits<double>::infinity());

/// Counts the map's occupied voxels and its ghost cells against the static truth
/// `static_scene` (map frame = scene frame). Multithreaded (OpenMP).
void countGhostCells(const Map& map, const geometry::MeshBvh& static_scene, bool octomap_threshold,
                     DynamicQuality& quality);

/// The ghost cells countGhostCells counts, their keys (in the map's block order).
[[nodiscard]] std::vector<VoxelKey> ghostCellKeys(const Map& map,
                                                  const geometry::MeshBvh& static_scene,
                                                  bool octomap_threshold);

}  // namespace fragg::sim
