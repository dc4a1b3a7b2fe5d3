// Launchers of the collision kernels (definitions in collision_kernels.cu). Every launcher runs
// on the given stream and checks the launch.
#pragma once

#include <cuda_runtime.h>

#include <cstdint>

#include "../collision_pose.h"
#include "../cuda_collision.h"
#include "../obstacle_masks.h"
#include "fragg_map/geometry/mesh_bvh.h"

namespace fragg::cuda {

/// Per pose, as the device writes it.
struct DeviceAnswer {
  uint32_t collides;
  uint32_t first_rank;  ///< mesh: rank of the first colliding candidate (UINT32_MAX: none)
  unsigned long long colliding_cells;
  VoxelKey first_cell;
};

/// One thread a pose: obstacle cells of its range in scan order, the exact test, stopping at
/// the first collision unless count_cells.
void launchPrimitiveCheck(const ObstacleMasksView& masks, const PrimitivePose* poses, uint32_t n,
                          double resolution_m, double half_m, bool count_cells,
                          DeviceAnswer* answers, cudaStream_t stream);

/// A chunk of poses prepared on the device, then checked: poses[0 .. count - 1] (pose first + i
/// of the batch) turned into prepared[i] by preparePrimitivePose, one thread a pose, then
/// checked as launchPrimitiveCheck does (the same kernel), answers[i] for each. A pose whose
/// cells leave the key range gets an empty answer and its batch index atomicMin'ed into
/// *first_bad. (Two kernels, not one: a kernel that prepares and checks held 194 registers a
/// thread, or spilled when held to 128; the check alone holds 125.)
void launchRigidPoseCheck(const ObstacleMasksView& masks, const RigidPose* poses, uint32_t first,
                          uint32_t count, const PrimitiveShape& shape, double half_m,
                          bool count_cells, PrimitivePose* prepared, CollisionAnswer* answers,
                          uint32_t* first_bad, cudaStream_t stream);

/// The mesh on the device: flat BVH, vertices and triangles in leaf order.
struct DeviceMesh {
  const geometry::MeshBvh::Node* nodes;
  const geometry::MeshBvh::Tri* tris;
  const int32_t* solid_of_slot;
  const Eigen::Vector3f* vertices_m;      ///< shape frame
  const Eigen::Vector3i* slot_triangles;  ///< vertex indices of each leaf slot's triangle
  uint32_t vertex_count;
  Eigen::Vector3f inside_dir;
};

/// One CUDA block a pose: the mesh's map-frame bounds -> lo / hi cell keys (as the CPU computes
/// them), and the number of obstacle cells in that range.
void launchMeshRanges(const DeviceMesh& mesh, const MeshPose* poses, uint32_t n,
                      const ObstacleMasksView& masks, double resolution_m, double grow_m,
                      VoxelKey* lo, VoxelKey* hi, uint32_t* counts, cudaStream_t stream);

/// One thread a pose: writes its obstacle cells, in scan order, from offsets[pose] on.
void launchMeshCandidates(const ObstacleMasksView& masks, const VoxelKey* lo, const VoxelKey* hi,
                          const uint64_t* offsets, uint32_t n, VoxelKey* cells,
                          uint32_t* pose_of_cell, cudaStream_t stream);

/// One thread a candidate cell: cut by a triangle (BVH cull, exact test), or inside a closed
/// mesh; colliding cells count into answers[pose] and the lowest rank wins first_rank.
void launchMeshTest(const DeviceMesh& mesh, const MeshCheck& check, const MeshPose* poses,
                    const VoxelKey* cells, const uint32_t* pose_of_cell, const uint64_t* offsets,
                    uint64_t total, DeviceAnswer* answers, uint32_t* overflow, cudaStream_t stream);

/// answers[p].first_cell = cells[offsets[p] + first_rank] where a pose collides.
void launchMeshFirstCells(const VoxelKey* cells, const uint64_t* offsets, uint32_t n,
                          DeviceAnswer* answers, cudaStream_t stream);

}  // namespace fragg::cuda
