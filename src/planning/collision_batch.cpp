#include "collision_batch.h"

#include <fmt/format.h>

#include <algorithm>
#include <cmath>
#include <cstdint>

#include "fragg_map/internal/thread_count.h"

namespace fragg::planning {

std::string poseError(const Eigen::Isometry3d& T_map_shape) {
  if (!T_map_shape.matrix().allFinite()) return "shape pose is not finite";
  const Eigen::Matrix3d R = T_map_shape.linear();
  const double err = (R.transpose() * R - Eigen::Matrix3d::Identity()).cwiseAbs().maxCoeff();
  if (err > 1e-6 || R.determinant() < 0.0)
    return fmt::format("shape pose rotation is not a rotation (orthonormality error {})", err);
  return {};
}

void validatedPoseBox(const std::vector<Eigen::Isometry3d>& T_map_shape, int threads,
                      Eigen::Vector3d* min_m, Eigen::Vector3d* max_m) {
  const int64_t n = static_cast<int64_t>(T_map_shape.size());
  int64_t first_bad = n;
  double min_x = INFINITY, min_y = INFINITY, min_z = INFINITY;
  double max_x = -INFINITY, max_y = -INFINITY, max_z = -INFINITY;
  // One pass: the check and the box read the same poses (a large batch: 100,000 poses are
  // 12.8 MB, read once instead of twice).
#pragma omp parallel for schedule(static) num_threads(threadCount(threads)) \
    reduction(min                                                           \
              : first_bad, min_x, min_y, min_z) reduction(max               \
                                                          : max_x, max_y, max_z) if (n > 4096)
  for (int64_t i = 0; i < n; ++i) {
    if (i < first_bad && !poseError(T_map_shape[i]).empty()) first_bad = i;
    const Eigen::Vector3d t = T_map_shape[i].translation();
    min_x = std::min(min_x, t.x());
    min_y = std::min(min_y, t.y());
    min_z = std::min(min_z, t.z());
    max_x = std::max(max_x, t.x());
    max_y = std::max(max_y, t.y());
    max_z = std::max(max_z, t.z());
  }
  if (first_bad < n) {
    const std::string why = poseError(T_map_shape[first_bad]);
    throw InvalidArgument(n == 1 ? why : fmt::format("pose {}: {}", first_bad, why));
  }
  *min_m = Eigen::Vector3d(min_x, min_y, min_z);
  *max_m = Eigen::Vector3d(max_x, max_y, max_z);
}

PrimitiveShape primitiveShape(const Map& map, const CollisionShape& shape,
                              const CollisionOptions& options) {
  PrimitiveShape s;
  s.box_half_m = shape.halfExtents() + Eigen::Vector3d::Constant(options.margin_m);
  s.radius_m = shape.radius() + options.margin_m;
  s.half_length_m = 0.5 * shape.length();
  s.resolution_m = map.resolution();
  switch (shape.kind()) {
    case ShapeKind::kBox:
      s.kind = PrimitiveKind::kBox;
      break;
    case ShapeKind::kSphere:
      s.kind = PrimitiveKind::kSphere;
      break;
    default:
      s.kind = PrimitiveKind::kCapsule;
      break;
  }
  return s;
}

InvalidArgument keyRangeError(size_t index) {
  return InvalidArgument(
      fmt::format("pose {}: the shape's cells are outside the map's key range", index));
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

void batchBlockRange(const Map& map, const CollisionShape& shape, const Eigen::Vector3d& min_m,
                     const Eigen::Vector3d& max_m, const CollisionOptions& options, BlockKey* lo,
                     BlockKey* hi) {
  // One cell of slack beyond the bounding sphere: the checks' own ranges come from rounded
  // arithmetic and must stay inside.
  const double reach_m = shape.boundingRadius() + options.margin_m + map.resolution();
  *lo = blockKeyOf(map.keyOf(min_m - Eigen::Vector3d::Constant(reach_m)));
  *hi = blockKeyOf(map.keyOf(max_m + Eigen::Vector3d::Constant(reach_m)));
}

}  // namespace fragg::planning
