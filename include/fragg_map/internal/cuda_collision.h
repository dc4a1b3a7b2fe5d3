// The CUDA collision checker as the planning tier sees it (no CUDA header): batches of poses
// over obstacle masks uploaded for the batch (internal/obstacle_masks.h). Defined in
// cuda/cuda_collision.cpp, linked only when built with CUDA (FRAGG_HAVE_CUDA); the planning
// tier calls makeCudaCollision only then.
#pragma once

#include <Eigen/Geometry>
#include <cstdint>
#include <memory>
#include <vector>

#include "fragg_map/geometry/mesh_bvh.h"
#include "fragg_map/internal/collision_pose.h"
#include "fragg_map/internal/obstacle_masks.h"

namespace fragg {

/// Host copies of an obstacle index's arrays.
struct ObstacleMasksHost {
  const std::vector<BlockKey>* keys = nullptr;   ///< the table (a power of two entries)
  const std::vector<int32_t>* slots = nullptr;   ///< per table entry
  const std::vector<uint64_t>* masks = nullptr;  ///< kMaskWords per slot
  uint64_t default_word = 0;
};

/// One pose's answer, as CollisionResult has it.
struct CollisionAnswer {
  bool collides = false;
  uint64_t colliding_cells = 0;
  VoxelKey first_cell;
};

/// A mesh pose: T_map_shape and its inverse (computed once on the host, so that both checkers
/// use the same bits).
struct MeshPose {
  Eigen::Matrix3d R_map_shape, R_shape_map;
  Eigen::Vector3d t_map_shape, t_shape_map;
};

struct MeshCheck {
  const geometry::MeshBvh* bvh = nullptr;
  bool closed = false;
  double resolution_m = 0.0;
  double grow_m = 0.0;  ///< margin: cells grown by it
  double half_m = 0.0;  ///< cell half size + grow_m - touching epsilon
  bool count_cells = false;
};

class CudaCollision {
 public:
  virtual ~CudaCollision() = default;
  /// Boxes, spheres, capsules: one answer per pose (half_m: cell half size less the touching
  /// epsilon).
  virtual std::vector<CollisionAnswer> checkPrimitives(const ObstacleMasksHost& masks,
                                                       const std::vector<PrimitivePose>& poses,
                                                       double resolution_m, double half_m,
                                                       bool count_cells) = 0;
  /// A triangle mesh at each pose. Throws InvalidArgument when an inside test meets more than
  /// 32 solids above a point.
  virtual std::vector<CollisionAnswer> checkMesh(const ObstacleMasksHost& masks,
                                                 const std::vector<MeshPose>& poses,
                                                 const MeshCheck& mesh) = 0;
};

/// Throws CudaError when the device cannot be used.
std::unique_ptr<CudaCollision> makeCudaCollision(int device);

}  // namespace fragg
