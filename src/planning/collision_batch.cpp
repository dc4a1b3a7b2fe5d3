#include "collision_batch.h"

#include <algorithm>

namespace fragg::planning {

PrimitivePose preparePrimitive(const Map& map, const CollisionShape& shape,
                               const Eigen::Isometry3d& T_map_shape,
                               const CollisionOptions& options) {
  PrimitivePose p;
  p.R_map_shape = T_map_shape.linear();
  p.centre_map = T_map_shape.translation();
  p.box_half_m = shape.halfExtents() + Eigen::Vector3d::Constant(options.margin_m);
  p.radius_m = shape.radius() + options.margin_m;
  const Eigen::Vector3d axis_map = p.R_map_shape.col(2) * (0.5 * shape.length());
  p.seg_a_map = p.centre_map - axis_map;
  p.seg_b_map = p.centre_map + axis_map;
  Eigen::Vector3d extent_m;
  switch (shape.kind()) {
    case ShapeKind::kBox:
      p.kind = PrimitiveKind::kBox;
      extent_m = p.R_map_shape.cwiseAbs() * p.box_half_m;
      break;
    case ShapeKind::kSphere:
      p.kind = PrimitiveKind::kSphere;
      extent_m = Eigen::Vector3d::Constant(p.radius_m);
      break;
    default:
      p.kind = PrimitiveKind::kCapsule;
      extent_m = axis_map.cwiseAbs() + Eigen::Vector3d::Constant(p.radius_m);
      break;
  }
  p.lo = map.keyOf(p.centre_map - extent_m);
  p.hi = map.keyOf(p.centre_map + extent_m);
  return p;
}

std::vector<MeshPose> meshPoses(const std::vector<Eigen::Isometry3d>& T_map_shape) {
  std::vector<MeshPose> out(T_map_shape.size());
  for (size_t i = 0; i < out.size(); ++i) {
    const Eigen::Isometry3d T_shape_map = T_map_shape[i].inverse();
    out[i].R_map_shape = T_map_shape[i].linear();
    out[i].t_map_shape = T_map_shape[i].translation();
    out[i].R_shape_map = T_shape_map.linear();
    out[i].t_shape_map = T_shape_map.translation();
  }
  return out;
}

MeshCheck meshCheck(const Map& map, const CollisionShape& shape, const CollisionOptions& options) {
  MeshCheck m;
  m.bvh = shape.meshBvh();
  m.closed = shape.meshClosed();
  m.resolution_m = map.resolution();
  m.grow_m = options.margin_m;
  m.half_m = 0.5 * map.resolution() + options.margin_m - kTouchEpsilon_m;
  m.count_cells = options.count_cells;
  return m;
}

void batchBlockRange(const Map& map, const CollisionShape& shape,
                     const std::vector<Eigen::Isometry3d>& T_map_shape,
                     const CollisionOptions& options, BlockKey* lo, BlockKey* hi) {
  // One cell of slack beyond the bounding sphere: the checks' own ranges come from rounded
  // arithmetic and must stay inside.
  const double reach_m = shape.boundingRadius() + options.margin_m + map.resolution();
  Eigen::Vector3d min_m = Eigen::Vector3d::Constant(INFINITY);
  Eigen::Vector3d max_m = Eigen::Vector3d::Constant(-INFINITY);
  for (const Eigen::Isometry3d& T : T_map_shape) {
    min_m = min_m.cwiseMin(T.translation());
    max_m = max_m.cwiseMax(T.translation());
  }
  *lo = blockKeyOf(map.keyOf(min_m - Eigen::Vector3d::Constant(reach_m)));
  *hi = blockKeyOf(map.keyOf(max_m + Eigen::Vector3d::Constant(reach_m)));
}

}  // namespace fragg::planning
