// One pose of a box, sphere or capsule as the collision checkers test it against cells, and the
// per-cell arithmetic both checkers share (FRAGG_HD): the CPU checker (src/planning) and the
// CUDA kernels (cuda/collision_kernels.cu) call the same functions on the same values, so their
// answers are identical. Prepared on the host (src/planning/collision_prep.cpp).
#pragma once

#include <Eigen/Core>
#include <Eigen/Geometry>

#include "fragg_map/geometry/cube_overlap.h"
#include "fragg_map/hd.h"
#include "fragg_map/key.h"

namespace fragg {

enum class PrimitiveKind : int32_t { kBox = 0, kSphere = 1, kCapsule = 2 };

struct PrimitivePose {
  Eigen::Matrix3d R_map_shape;           ///< box axes
  Eigen::Vector3d centre_map;            ///< shape origin
  Eigen::Vector3d box_half_m;            ///< box: half extents grown by the margin
  Eigen::Vector3d seg_a_map, seg_b_map;  ///< capsule axis ends
  double radius_m = 0.0;                 ///< sphere / capsule radius grown by the margin
  VoxelKey lo, hi;                       ///< cells the shape's map-frame box covers (inclusive)
  PrimitiveKind kind = PrimitiveKind::kBox;
};

/// Centre of a cell, as Map::centerOf computes it.
FRAGG_HD Eigen::Vector3d cellCentre(const VoxelKey& k, double resolution_m) {
  return Eigen::Vector3d((static_cast<double>(k.x) + 0.5) * resolution_m,
                         (static_cast<double>(k.y) + 0.5) * resolution_m,
                         (static_cast<double>(k.z) + 0.5) * resolution_m);
}

/// R p + t, one fixed order of operations (both checkers transform mesh vertices with it).
FRAGG_HD Eigen::Vector3d transformPoint(const Eigen::Matrix3d& R, const Eigen::Vector3d& t,
                                        const Eigen::Vector3d& p) {
  return Eigen::Vector3d(R(0, 0) * p[0] + R(0, 1) * p[1] + R(0, 2) * p[2] + t[0],
                         R(1, 0) * p[0] + R(1, 1) * p[1] + R(1, 2) * p[2] + t[1],
                         R(2, 0) * p[0] + R(2, 1) * p[1] + R(2, 2) * p[2] + t[2]);
}

/// Whether the shape meets the cube centre +- half_m (half_m: the cell's half size less the
/// touching epsilon).
FRAGG_HD bool primitiveOverlapsCell(const PrimitivePose& p, const Eigen::Vector3d& centre,
                                    double half_m) {
  switch (p.kind) {
    case PrimitiveKind::kBox:
      return geometry::orientedBoxCubeOverlap(p.centre_map, p.R_map_shape, p.box_half_m, centre,
                                              half_m);
    case PrimitiveKind::kSphere:
      return geometry::pointCubeDistanceSq(p.centre_map, centre, half_m) <= p.radius_m * p.radius_m;
    default:
      return geometry::segmentCubeDistanceSq(p.seg_a_map, p.seg_b_map, centre, half_m) <=
             p.radius_m * p.radius_m;
  }
}

}  // namespace fragg
