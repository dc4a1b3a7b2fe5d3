// Mesh poses: the triangle/cube test after a per-triangle box cull, then ray parity for the
// cells no triangle reaches. Internal to fragg_map_planning.
#pragma once

#include <Eigen/Geometry>

#include "fragg_map/map.h"
#include "fragg_map/planning/collision_check.h"
#include "obstacle_masks.h"

namespace fragg::planning {

CollisionResult checkMeshPose(const Map& map, const ObstacleMasksView& masks,
                              const CollisionShape& shape, const Eigen::Isometry3d& T_map_shape,
                              const CollisionOptions& options);

}  // namespace fragg::planning
