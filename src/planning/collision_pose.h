// One pose of a box, sphere or capsule as the collision checkers test it against cells, and the
// per-cell arithmetic both checkers share (FRAGG_HD): the CPU checker (src/planning) and the
// CUDA kernels (cuda/collision_kernels.cu) call the same functions on the same values, so their
// answers are identical. A pose is prepared by preparePrimitivePose, on the host (the CPU
// checker and the CUDA checker's host staging, src/planning/collision_check.cpp) or in a CUDA
// kernel (CollisionOptions::pose_preparation = kDevice): the same function on the same bits, so
// both give the same PrimitivePose.
#pragma once

#include <Eigen/Core>
#include <Eigen/Geometry>
#include <cmath>
#include <cstdint>

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

/// What every pose of a batch shares: the shape's kind and sizes grown by the margin, and the
/// map's resolution.
struct PrimitiveShape {
  PrimitiveKind kind = PrimitiveKind::kBox;
  Eigen::Vector3d box_half_m = Eigen::Vector3d::Zero();  ///< box half extents + margin
  double radius_m = 0.0;                                 ///< sphere / capsule radius + margin
  double half_length_m = 0.0;  ///< capsule: half the axis length (0 otherwise)
  double resolution_m = 0.0;   ///< the map's cell size
};

/// A pose as a batch uploads it when the device prepares it: the caller's rotation and
/// translation, bits unchanged (96 bytes, against a PrimitivePose's 208).
struct RigidPose {
  Eigen::Matrix3d R_map_shape;
  Eigen::Vector3d t_map_shape;
};

/// The cell holding p_map, as Map::keyOf computes it ((p / resolution) floored); false where
/// Map::keyOf throws (not finite, or beyond the int32 key range).
[[nodiscard]] FRAGG_HD bool cellKeyOf(const Eigen::Vector3d& p_map, double resolution_m,
                                      VoxelKey* key) {
  int32_t k[3];
  for (int a = 0; a < 3; ++a) {
    const double v = p_map[a] / resolution_m;
    if (!(v < 2147483647.0 && v > -2147483647.0)) return false;  // NaN fails both
    k[a] = static_cast<int32_t>(floor(v));
  }
  *key = VoxelKey{k[0], k[1], k[2]};
  return true;
}

/// The shape at (R_map_shape, t_map_shape) as the cell tests see it: axes, centre, grown sizes,
/// capsule axis ends and the cells its map-frame box covers. Scalar arithmetic in one fixed
/// order (no Eigen expression whose order could differ between host and device), so the host
/// and the CUDA kernel compute the same bits. False when the cell range leaves the map's key
/// range (*pose is then incomplete).
[[nodiscard]] FRAGG_HD bool preparePrimitivePose(const PrimitiveShape& shape,
                                                 const Eigen::Matrix3d& R_map_shape,
                                                 const Eigen::Vector3d& t_map_shape,
                                                 PrimitivePose* pose) {
  PrimitivePose& p = *pose;
  p.R_map_shape = R_map_shape;
  p.centre_map = t_map_shape;
  p.box_half_m = shape.box_half_m;
  p.radius_m = shape.radius_m;
  p.kind = shape.kind;
  Eigen::Vector3d extent_m;
  for (int a = 0; a < 3; ++a) {
    const double axis_m = R_map_shape(a, 2) * shape.half_length_m;
    p.seg_a_map[a] = t_map_shape[a] - axis_m;
    p.seg_b_map[a] = t_map_shape[a] + axis_m;
    switch (shape.kind) {
      case PrimitiveKind::kBox:
        extent_m[a] = fabs(R_map_shape(a, 0)) * shape.box_half_m[0] +
                      fabs(R_map_shape(a, 1)) * shape.box_half_m[1] +
                      fabs(R_map_shape(a, 2)) * shape.box_half_m[2];
        break;
      case PrimitiveKind::kSphere:
        extent_m[a] = shape.radius_m;
        break;
      default:
        extent_m[a] = fabs(axis_m) + shape.radius_m;
        break;
    }
  }
  const Eigen::Vector3d lo_m(t_map_shape[0] - extent_m[0], t_map_shape[1] - extent_m[1],
                             t_map_shape[2] - extent_m[2]);
  const Eigen::Vector3d hi_m(t_map_shape[0] + extent_m[0], t_map_shape[1] + extent_m[1],
                             t_map_shape[2] + extent_m[2]);
  return cellKeyOf(lo_m, shape.resolution_m, &p.lo) && cellKeyOf(hi_m, shape.resolution_m, &p.hi);
}

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
