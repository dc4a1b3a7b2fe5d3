// Closed triangle meshes of the scene primitives (one solid each), in metres. Every mesh is
// watertight with outward-facing triangles, so that ray parity decides "inside".
#pragma once

#include <Eigen/Core>
#include <functional>

#include "fragg_map/geometry/triangle_mesh.h"

namespace fragg::sim {

/// An axis-aligned box.
geometry::TriangleMesh makeBox(const Eigen::Vector3d& min_m, const Eigen::Vector3d& max_m);

/// A box of half extents `half_m` about `centre_m`, turned by `yaw_rad` about z (walls).
geometry::TriangleMesh makeOrientedBox(const Eigen::Vector3d& centre_m,
                                       const Eigen::Vector3d& half_m, double yaw_rad);

/// A capped cylinder from `a_m` to `b_m` (any direction) with `segments` sides.
geometry::TriangleMesh makeCylinder(const Eigen::Vector3d& a_m, const Eigen::Vector3d& b_m,
                                    double radius_m, int segments = 24);

/// A UV sphere with `rings` latitude bands and `segments` longitude sectors.
geometry::TriangleMesh makeSphere(const Eigen::Vector3d& centre_m, double radius_m, int rings = 12,
                                  int segments = 24);

/// A slab over [x0, x1] x [y0, y1] whose top is the terrain height_m(x, y) sampled on a grid
/// of `cell_m` and whose flat bottom is `thickness_m` below the lowest terrain sample.
geometry::TriangleMesh makeTerrainSlab(double x0, double y0, double x1, double y1, double cell_m,
                                       double thickness_m,
                                       const std::function<double(double, double)>& height_m);

}  // namespace fragg::sim
