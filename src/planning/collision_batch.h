// Host-side preparation of a collision batch, shared by the CPU and CUDA checkers: each
// primitive pose as the cell tests see it, mesh poses with their inverses, and the block range
// a batch's obstacle index must cover. Internal to fragg_map_planning.
#pragma once

#include <Eigen/Geometry>
#include <vector>

#include "cuda_collision.h"
#include "fragg_map/map.h"
#include "fragg_map/planning/collision_check.h"

namespace fragg::planning {

/// Box, sphere or capsule at T_map_shape, grown by the margin, with its cell range.
PrimitivePose preparePrimitive(const Map& map, const CollisionShape& shape,
                               const Eigen::Isometry3d& T_map_shape,
                               const CollisionOptions& options);

std::vector<MeshPose> meshPoses(const std::vector<Eigen::Isometry3d>& T_map_shape);
MeshCheck meshCheck(const Map& map, const CollisionShape& shape, const CollisionOptions& options);

/// Blocks that hold every cell any pose's check may look at: the shape's bounding sphere
/// (grown by the margin) about each pose.
void batchBlockRange(const Map& map, const CollisionShape& shape,
                     const std::vector<Eigen::Isometry3d>& T_map_shape,
                     const CollisionOptions& options, BlockKey* lo, BlockKey* hi);

}  // namespace fragg::planning
