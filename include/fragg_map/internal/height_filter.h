// The insert-time height filter (MapParams::height_filter): drops points by their map-frame z.
#pragma once

#include <Eigen/Geometry>
#include <cstddef>

#include "fragg_map/map_params.h"
#include "fragg_map/point_cloud.h"

namespace fragg {

/// Copies into `out` the points of `cloud` (sensor frame) whose map-frame height through
/// `T_map_sensor` lies in [band.min_z_m, band.max_z_m]; returns how many were dropped.
/// An unorganised cloud loses the dropped points. An organised cloud keeps its layout: a
/// dropped pixel becomes (0, 0, 0), which the map skips as invalid and never turns into a
/// no-return ray (a NaN would, with clear_no_return_rays, and would clear space towards the
/// floor a user filtered out). Non-finite points are kept as they are (not counted).
size_t filterHeight(const PointCloud& cloud, const Eigen::Isometry3d& T_map_sensor,
                    const HeightFilterParams& band, PointCloud* out);

}  // namespace fragg
