#include "collision_batch.h"

#include <algorithm>
#include <cmath>
#include <cstdint>

#include "fragg_map/internal/thread_count.h"

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
  // The poses' box on the batch's threads (a large batch: a serial pass over 100,000 poses is
  // a noticeable part of a CUDA batch's host work).
  const int64_t n = static_cast<int64_t>(T_map_shape.size());
  double min_x = INFINITY, min_y = INFINITY, min_z = INFINITY;
  double max_x = -INFINITY, max_y = -INFINITY, max_z = -INFINITY;
#pragma omp parallel for schedule(static) num_threads(threadCount(options.threads)) \
    reduction(min                                                                   \
              : min_x, min_y, min_z) reduction(max                                  \
                                               : max_x, max_y, max_z) if (n > 16384)
  for (int64_t i = 0; i < n; ++i) {
    const Eigen::Vector3d t = T_map_shape[i].translation();
    min_x = std::min(min_x, t.x());
    min_y = std::min(min_y, t.y());
    min_z = std::min(min_z, t.z());
    max_x = std::max(max_x, t.x());
    max_y = std::max(max_y, t.y());
    max_z = std::max(max_z, t.z());
  }
  const Eigen::Vector3d min_m(min_x, min_y, min_z), max_m(max_x, max_y, max_z);
  *lo = blockKeyOf(map.keyOf(min_m - Eigen::Vector3d::Constant(reach_m)));
  *hi = blockKeyOf(map.keyOf(max_m + Eigen::Vector3d::Constant(reach_m)));
}

}  // namespace fragg::planning
