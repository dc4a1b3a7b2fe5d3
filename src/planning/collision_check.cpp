#include "fragg_map/planning/collision_check.h"

#include <fmt/format.h>
#include <omp.h>

#include <cmath>
#include <exception>

#include "fragg_map/errors.h"
#include "fragg_map/geometry/cube_overlap.h"
#include "mesh_collision.h"
#include "obstacle_cells.h"

namespace fragg::planning {

namespace {

// Box, sphere, capsule: the shape's map-frame box gives the cell range, every obstacle cell in
// it gets the exact test against its cube shrunk by the touching epsilon.
CollisionResult checkPrimitivePose(const Map& map, const BlockView& view,
                                   const CollisionShape& shape,
                                   const Eigen::Isometry3d& T_map_shape,
                                   const CollisionOptions& options) {
  const double half_m = 0.5 * map.resolution() - kTouchEpsilon_m;
  const Eigen::Matrix3d R = T_map_shape.linear();
  const Eigen::Vector3d centre_map = T_map_shape.translation();
  const Eigen::Vector3d box_half_m =
      shape.halfExtents() + Eigen::Vector3d::Constant(options.margin_m);
  const double radius_m = shape.radius() + options.margin_m;
  const Eigen::Vector3d axis_map = R.col(2) * (0.5 * shape.length());
  const Eigen::Vector3d seg_a = centre_map - axis_map, seg_b = centre_map + axis_map;

  Eigen::Vector3d extent_m;
  switch (shape.kind()) {
    case ShapeKind::kBox:
      extent_m = R.cwiseAbs() * box_half_m;
      break;
    case ShapeKind::kSphere:
      extent_m = Eigen::Vector3d::Constant(radius_m);
      break;
    default:  // capsule
      extent_m = axis_map.cwiseAbs() + Eigen::Vector3d::Constant(radius_m);
      break;
  }
  const VoxelKey lo = map.keyOf(centre_map - extent_m);
  const VoxelKey hi = map.keyOf(centre_map + extent_m);

  const auto overlaps = [&](const Eigen::Vector3d& cell_centre) {
    switch (shape.kind()) {
      case ShapeKind::kBox:
        return geometry::orientedBoxCubeOverlap(centre_map, R, box_half_m, cell_centre, half_m);
      case ShapeKind::kSphere:
        return geometry::pointCubeDistanceSq(centre_map, cell_centre, half_m) <=
               radius_m * radius_m;
      default:
        return geometry::segmentCubeDistanceSq(seg_a, seg_b, cell_centre, half_m) <=
               radius_m * radius_m;
    }
  };
  CollisionResult result;
  forEachObstacleCell(map, view, lo, hi, options.unknown_is_occupied, [&](const VoxelKey& k) {
    if (!overlaps(map.centerOf(k))) return false;
    if (!result.collides) result.first_cell = k;
    result.collides = true;
    ++result.colliding_cells;
    return !options.count_cells;
  });
  return result;
}

CollisionResult checkValidated(const Map& map, const BlockView& view, const CollisionShape& shape,
                               const Eigen::Isometry3d& T_map_shape,
                               const CollisionOptions& options) {
  if (shape.kind() == ShapeKind::kMesh)
    return checkMeshPose(map, view, shape, T_map_shape, options);
  return checkPrimitivePose(map, view, shape, T_map_shape, options);
}

}  // namespace

void validate(const CollisionOptions& options) {
  if (!std::isfinite(options.margin_m) || options.margin_m < 0.0)
    throw InvalidArgument(
        fmt::format("collision margin must be finite and >= 0, got {}", options.margin_m));
  if (options.threads < 0)
    throw InvalidArgument(fmt::format("threads must be >= 0, got {}", options.threads));
}

void validatePose(const Eigen::Isometry3d& T_map_shape) {
  if (!T_map_shape.matrix().allFinite()) throw InvalidArgument("shape pose is not finite");
  const Eigen::Matrix3d R = T_map_shape.linear();
  const double err = (R.transpose() * R - Eigen::Matrix3d::Identity()).cwiseAbs().maxCoeff();
  if (err > 1e-6 || R.determinant() < 0.0)
    throw InvalidArgument(
        fmt::format("shape pose rotation is not a rotation (orthonormality error {})", err));
}

CollisionResult checkPose(const Map& map, const CollisionShape& shape,
                          const Eigen::Isometry3d& T_map_shape, const CollisionOptions& options) {
  validate(options);
  validatePose(T_map_shape);
  return checkValidated(map, map.blockView(), shape, T_map_shape, options);
}

std::vector<CollisionResult> checkPoses(const Map& map, const CollisionShape& shape,
                                        const std::vector<Eigen::Isometry3d>& T_map_shape,
                                        const CollisionOptions& options) {
  validate(options);
  for (const Eigen::Isometry3d& T : T_map_shape) validatePose(T);
  const BlockView view = map.blockView();
  std::vector<CollisionResult> results(T_map_shape.size());
  std::exception_ptr error;
  const int threads = options.threads > 0 ? options.threads : omp_get_max_threads();
  const int64_t n = static_cast<int64_t>(T_map_shape.size());
#pragma omp parallel for schedule(dynamic, 1) num_threads(threads)
  for (int64_t i = 0; i < n; ++i) {
    try {
      results[i] = checkValidated(map, view, shape, T_map_shape[i], options);
    } catch (...) {
#pragma omp critical(fragg_collision_error)
      if (!error) error = std::current_exception();
    }
  }
  if (error) std::rethrow_exception(error);
  return results;
}

}  // namespace fragg::planning
