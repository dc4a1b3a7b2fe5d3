// Host-side preparation of a collision batch, shared by the CPU and CUDA checkers: the poses
// checked, what a batch's primitive poses share (each pose then prepared by
// preparePrimitivePose, collision_pose.h), mesh poses with their inverses, and the block range
// a batch's obstacle index must cover. Internal to fragg_map_planning.
#pragma once

#include <Eigen/Geometry>
#include <string>
#include <vector>

#include "cuda_collision.h"
#include "fragg_map/errors.h"
#include "fragg_map/map.h"
#include "fragg_map/planning/collision_check.h"

namespace fragg::planning {

/// What a batch's box, sphere or capsule poses share (the shape grown by the margin, the
/// map's resolution); preparePrimitivePose() turns one pose into a PrimitivePose with it.
[[nodiscard]] PrimitiveShape primitiveShape(const Map& map, const CollisionShape& shape,
                                            const CollisionOptions& options);

/// The error for pose `index` whose cells leave the map's key range (host and device paths).
[[nodiscard]] InvalidArgument keyRangeError(size_t index);

/// Why `T_map_shape` is not a rigid pose (empty: it is one).
[[nodiscard]] std::string poseError(const Eigen::Isometry3d& T_map_shape);

/// The translations' bounding box of a batch, every pose checked on the way (one pass over the
/// poses on `threads` threads): throws InvalidArgument for the first bad pose by index, naming
/// it (validatePose's message).
void validatedPoseBox(const std::vector<Eigen::Isometry3d>& T_map_shape, int threads,
                      Eigen::Vector3d* min_m, Eigen::Vector3d* max_m);

std::vector<MeshPose> meshPoses(const std::vector<Eigen::Isometry3d>& T_map_shape);
MeshCheck meshCheck(const Map& map, const CollisionShape& shape, const CollisionOptions& options);

/// Blocks that hold every cell any pose's check may look at: the shape's bounding sphere
/// (grown by the margin) about each pose, whose translations lie in [min_m, max_m]
/// (validatedPoseBox).
void batchBlockRange(const Map& map, const CollisionShape& shape, const Eigen::Vector3d& min_m,
                     const Eigen::Vector3d& max_m, const CollisionOptions& options, BlockKey* lo,
                     BlockKey* hi);

}  // namespace fragg::planning
