// The CUDA collision checker as the rest of planning sees it (no CUDA header): batches of poses
// over obstacle masks (obstacle_masks.h), either read in place from the map's device layer view
// or uploaded for the batch from a host obstacle index. Defined in
// src/planning/cuda/cuda_collision.cpp (planning's CUDA part), linked only when built with CUDA
// (FRAGG_HAVE_CUDA); the rest of planning calls makeCudaCollision only then. Its buffers come
// from a DeviceScratch: the map's (lent with its device view), so the checker's state is the
// map's, on the map's device.
#pragma once

#include <Eigen/Geometry>
#include <cstdint>
#include <functional>
#include <memory>
#include <vector>

#include "collision_pose.h"
#include "fragg_map/device_scratch.h"
#include "fragg_map/geometry/mesh_bvh.h"
#include "obstacle_masks.h"

namespace fragg {

/// Host copies of an obstacle index's arrays.
struct ObstacleMasksHost {
  const std::vector<BlockKey>* keys = nullptr;   ///< the table (a power of two entries)
  const std::vector<int32_t>* slots = nullptr;   ///< per table entry
  const std::vector<uint64_t>* masks = nullptr;  ///< kMaskWords per slot
  uint64_t default_word = 0;
};

/// A batch's obstacles as the checker gets them: host arrays to upload, or masks already on the
/// scratch's device (layerObstacles over the map's device layer view).
struct ObstacleSource {
  const ObstacleMasksHost* host = nullptr;
  ObstacleMasksView device;  ///< used when host is null
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

/// Writes poses first .. first + count - 1 of a batch to out[0 .. count - 1].
using RigidPosePacker = std::function<void(size_t first, size_t count, RigidPose* out)>;

class CudaCollision {
 public:
  virtual ~CudaCollision() = default;
  /// Pinned host room for `n` box, sphere or capsule poses, which the caller fills (on as many
  /// threads as it likes) before checkPrimitives(); valid until the next call.
  virtual PrimitivePose* primitiveStaging(size_t n) = 0;
  /// Boxes, spheres, capsules: the `n` poses staged, one answer per pose (half_m: cell half
  /// size less the touching epsilon).
  virtual std::vector<CollisionAnswer> checkPrimitives(const ObstacleSource& masks, size_t n,
                                                       double resolution_m, double half_m,
                                                       bool count_cells) = 0;
  /// Boxes, spheres, capsules prepared on the device: the kernel turns each pose into its
  /// PrimitivePose with preparePrimitivePose (the function the host calls: the same bits), so
  /// only the rigid poses travel (96 bytes a pose). `pack(first, count, out)` writes poses
  /// first .. first + count - 1 of the batch to out[0 .. count - 1] (pinned memory); the
  /// checker asks for them in chunks of `chunk_poses` and uploads and checks chunk k (its
  /// answers copied back) while chunk k + 1 is packed. Returns the `n` answers in pinned memory,
  /// valid until the next call; *first_bad gets the first pose (by index) whose cells leave the
  /// map's key range, `n` when none (its answer is then meaningless).
  [[nodiscard]] virtual const CollisionAnswer* checkRigidPoses(
      const ObstacleSource& masks, size_t n, const PrimitiveShape& shape, double half_m,
      bool count_cells, size_t chunk_poses, const RigidPosePacker& pack, size_t* first_bad) = 0;
  /// A triangle mesh at each pose. Throws InvalidArgument when an inside test meets more than
  /// 32 solids above a point.
  virtual std::vector<CollisionAnswer> checkMesh(const ObstacleSource& masks,
                                                 const std::vector<MeshPose>& poses,
                                                 const MeshCheck& mesh) = 0;
};

/// A checker working in `scratch` (on its device and stream; it must outlive the checker).
/// Throws CudaError when the device cannot be used.
std::unique_ptr<CudaCollision> makeCudaCollision(DeviceScratch& scratch);

}  // namespace fragg
