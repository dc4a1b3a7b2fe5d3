// Closed triangle meshes of simple solids, for collision checks and benchmarks.
#pragma once

#include <Eigen/Core>

#include "fragg_map/geometry/triangle_mesh.h"

namespace fragg::geometry {

/// A closed ellipsoid centred on the origin with these semi-axes (metres): two poles and
/// rings - 1 rings of `segments` vertices, 2 segments (rings - 1) triangles, one solid.
/// Throws InvalidArgument for rings < 2, segments < 3 or a semi-axis that is not > 0.
TriangleMesh ellipsoidMesh(const Eigen::Vector3f& semi_axes_m, int rings, int segments);

}  // namespace fragg::geometry
