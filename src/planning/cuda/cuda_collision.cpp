// The CUDA collision checker: reads the batch's obstacle masks from the map's device layer view
// (or uploads those of a host obstacle index), uploads the poses, runs the collision kernels and
// reads the answers back. Its buffers are numbered buffers of a DeviceScratch.
#include "../cuda_collision.h"

#include <algorithm>
#include <memory>
#include <vector>

#include "collision_kernels.h"
#include "cuda_check.h"
#include "cuda_stream.h"
#include "fragg_map/errors.h"

namespace fragg {
namespace cuda {
namespace {

/// The checker's buffers in its scratch (device buffer ids).
enum Buffer : int {
  kKeys = 100,
  kSlots,
  kMasks,
  kPrimitivePoses,
  kMeshPoses,
  kAnswers,
  kLo,
  kHi,
  kCells,
  kCounts,
  kPoseOfCell,
  kOverflow,
  kOffsets,
  kNodes,
  kTris,
  kSolids,
  kVertices,
  kSlotTriangles,
  kRigidPoses,
  kRigidAnswers,
  kFirstBad,
};
/// Pinned host buffers (their own numbering).
enum PinnedBuffer : int {
  kAnswersHost = 100,
  kStagedPoses,
  kStagedRigidPoses,
  kRigidAnswersHost,
  kFirstBadHost
};

class CudaCollisionImpl final : public CudaCollision {
 public:
  explicit CudaCollisionImpl(DeviceScratch& scratch)
      : s_(scratch), stream_(static_cast<cudaStream_t>(scratch.stream())) {
    FRAGG_CUDA_CHECK(cudaSetDevice(scratch.device()));
  }

  PrimitivePose* primitiveStaging(size_t n) override {
    return s_.pinned<PrimitivePose>(kStagedPoses, n);
  }

  std::vector<CollisionAnswer> checkPrimitives(const ObstacleSource& masks, size_t count,
                                               double resolution_m, double half_m,
                                               bool count_cells) override {
    const uint32_t n = static_cast<uint32_t>(count);
    const ObstacleMasksView view = obstacles(masks);
    PrimitivePose* d_poses = s_.device<PrimitivePose>(kPrimitivePoses, n);
    DeviceAnswer* d_answers = s_.device<DeviceAnswer>(kAnswers, n);
    copyToDevice(d_poses, s_.pinned<PrimitivePose>(kStagedPoses, n), n, stream_);
    launchPrimitiveCheck(view, d_poses, n, resolution_m, half_m, count_cells, d_answers, stream_);
    return download(d_answers, n, count_cells);
  }

  const CollisionAnswer* checkRigidPoses(const ObstacleSource& masks, size_t count,
                                         const PrimitiveShape& shape, double half_m,
                                         bool count_cells, size_t chunk_poses,
                                         const RigidPosePacker& pack, size_t* first_bad) override {
    const ObstacleMasksView view = obstacles(masks);
    RigidPose* staged = s_.pinned<RigidPose>(kStagedRigidPoses, count);
    CollisionAnswer* answers = s_.pinned<CollisionAnswer>(kRigidAnswersHost, count);
    uint32_t* bad = s_.pinned<uint32_t>(kFirstBadHost, 1);
    RigidPose* d_poses = s_.device<RigidPose>(kRigidPoses, count);
    PrimitivePose* d_prepared = s_.device<PrimitivePose>(kPrimitivePoses, count);
    CollisionAnswer* d_answers = s_.device<CollisionAnswer>(kRigidAnswers, count);
    uint32_t* d_bad = s_.device<uint32_t>(kFirstBad, 1);
    FRAGG_CUDA_CHECK(cudaMemsetAsync(d_bad, 0xff, sizeof(uint32_t), stream_));
    // The poses' copies on a stream of their own, so that chunk k + 1's copy runs beside chunk
    // k's kernels (a copy engine and the SMs); the kernels of a chunk wait for its copy.
    if (!copies_) {
      copies_ = std::make_unique<CudaStream>();
      copied_ = std::make_unique<CudaEvent>();
    }
    const size_t chunk = std::max<size_t>(chunk_poses, 1);
    // Chunk k's copy, kernels and answers are queued (asynchronous) before chunk k + 1 is packed:
    // the device works on k while the host threads pack k + 1.
    for (size_t first = 0; first < count; first += chunk) {
      const size_t n = std::min(chunk, count - first);
      pack(first, n, staged + first);
      copyToDevice(d_poses + first, staged + first, n, copies_->get());
      copied_->record(copies_->get());
      copied_->makeWait(stream_);
      launchRigidPoseCheck(view, d_poses + first, static_cast<uint32_t>(first),
                           static_cast<uint32_t>(n), shape, half_m, count_cells, d_prepared + first,
                           d_answers + first, d_bad, stream_);
      copyToHost(answers + first, d_answers + first, n, stream_);
    }
    copyToHost(bad, d_bad, 1, stream_);
    FRAGG_CUDA_CHECK(cudaStreamSynchronize(stream_));
    *first_bad = *bad == UINT32_MAX ? count : *bad;
    return answers;
  }

  std::vector<CollisionAnswer> checkMesh(const ObstacleSource& masks,
                                         const std::vector<MeshPose>& poses,
                                         const MeshCheck& check) override {
    const uint32_t n = static_cast<uint32_t>(poses.size());
    const ObstacleMasksView view = obstacles(masks);
    const DeviceMesh mesh = uploadMesh(*check.bvh);
    MeshPose* d_poses = s_.device<MeshPose>(kMeshPoses, n);
    VoxelKey* d_lo = s_.device<VoxelKey>(kLo, n);
    VoxelKey* d_hi = s_.device<VoxelKey>(kHi, n);
    uint32_t* d_counts = s_.device<uint32_t>(kCounts, n);
    uint64_t* d_offsets = s_.device<uint64_t>(kOffsets, n + 1);
    DeviceAnswer* d_answers = s_.device<DeviceAnswer>(kAnswers, n);
    copyToDevice(d_poses, poses.data(), n, stream_);
    launchMeshRanges(mesh, d_poses, n, view, check.resolution_m, check.grow_m, d_lo, d_hi, d_counts,
                     stream_);
    std::vector<uint32_t> counts(n);
    copyToHost(counts.data(), d_counts, n, stream_);
    FRAGG_CUDA_CHECK(cudaStreamSynchronize(stream_));
    std::vector<uint64_t> offsets(n + 1, 0);
    for (uint32_t i = 0; i < n; ++i) offsets[i + 1] = offsets[i] + counts[i];
    const uint64_t total = offsets[n];
    copyToDevice(d_offsets, offsets.data(), n + 1, stream_);
    VoxelKey* d_cells = s_.device<VoxelKey>(kCells, total);
    uint32_t* d_pose_of_cell = s_.device<uint32_t>(kPoseOfCell, total);
    launchMeshCandidates(view, d_lo, d_hi, d_offsets, n, d_cells, d_pose_of_cell, stream_);
    std::vector<DeviceAnswer> init(n, DeviceAnswer{0, UINT32_MAX, 0, VoxelKey{}});
    copyToDevice(d_answers, init.data(), n, stream_);
    uint32_t* d_overflow = s_.device<uint32_t>(kOverflow, 1);
    FRAGG_CUDA_CHECK(cudaMemsetAsync(d_overflow, 0, sizeof(uint32_t), stream_));
    launchMeshTest(mesh, check, d_poses, d_cells, d_pose_of_cell, d_offsets, total, d_answers,
                   d_overflow, stream_);
    launchMeshFirstCells(d_cells, d_offsets, n, d_answers, stream_);
    uint32_t overflow = 0;
    copyToHost(&overflow, d_overflow, 1, stream_);
    std::vector<CollisionAnswer> out = download(d_answers, n, check.count_cells);
    if (overflow) throw InvalidArgument("inside test: more than 32 solids above one point");
    return out;
  }

 private:
  /// The device masks of the batch: the layer view as it is, or the host index uploaded.
  ObstacleMasksView obstacles(const ObstacleSource& source) {
    if (!source.host) return source.device;
    const ObstacleMasksHost& m = *source.host;
    BlockKey* keys = s_.device<BlockKey>(kKeys, m.keys->size());
    int32_t* slots = s_.device<int32_t>(kSlots, m.slots->size());
    uint64_t* masks = s_.device<uint64_t>(kMasks, m.masks->size());
    copyToDevice(keys, m.keys->data(), m.keys->size(), stream_);
    copyToDevice(slots, m.slots->data(), m.slots->size(), stream_);
    copyToDevice(masks, m.masks->data(), m.masks->size(), stream_);
    ObstacleMasksView v;
    v.keys = keys;
    v.slots = slots;
    v.masks = masks;
    v.capacity_mask = static_cast<uint32_t>(m.keys->size() - 1);
    v.default_word = m.default_word;
    return v;
  }

  DeviceMesh uploadMesh(const geometry::MeshBvh& bvh) {
    const geometry::TriangleMesh& mesh = bvh.mesh();
    std::vector<Eigen::Vector3i> slot_triangles(bvh.leafOrder().size());
    for (size_t s = 0; s < slot_triangles.size(); ++s)
      slot_triangles[s] = mesh.triangles[bvh.leafOrder()[s]];
    DeviceMesh d;
    auto* nodes = s_.device<geometry::MeshBvh::Node>(kNodes, bvh.nodes().size());
    auto* tris = s_.device<geometry::MeshBvh::Tri>(kTris, bvh.leafTriangles().size());
    auto* solids = s_.device<int32_t>(kSolids, bvh.leafSolids().size());
    auto* vertices = s_.device<Eigen::Vector3f>(kVertices, mesh.vertices_m.size());
    auto* triangles = s_.device<Eigen::Vector3i>(kSlotTriangles, slot_triangles.size());
    copyToDevice(nodes, bvh.nodes().data(), bvh.nodes().size(), stream_);
    copyToDevice(tris, bvh.leafTriangles().data(), bvh.leafTriangles().size(), stream_);
    copyToDevice(solids, bvh.leafSolids().data(), bvh.leafSolids().size(), stream_);
    copyToDevice(vertices, mesh.vertices_m.data(), mesh.vertices_m.size(), stream_);
    copyToDevice(triangles, slot_triangles.data(), slot_triangles.size(), stream_);
    // The host vector must outlive the asynchronous copy.
    FRAGG_CUDA_CHECK(cudaStreamSynchronize(stream_));
    d.nodes = nodes;
    d.tris = tris;
    d.solid_of_slot = solids;
    d.vertices_m = vertices;
    d.slot_triangles = triangles;
    d.vertex_count = static_cast<uint32_t>(mesh.vertices_m.size());
    d.inside_dir = geometry::MeshBvh::insideRayDirection();
    return d;
  }

  std::vector<CollisionAnswer> download(const DeviceAnswer* d_answers, uint32_t n,
                                        bool count_cells) {
    DeviceAnswer* answers = s_.pinned<DeviceAnswer>(kAnswersHost, n);
    copyToHost(answers, d_answers, n, stream_);
    FRAGG_CUDA_CHECK(cudaStreamSynchronize(stream_));
    std::vector<CollisionAnswer> out(n);
    for (uint32_t i = 0; i < n; ++i) {
      out[i].collides = answers[i].collides != 0;
      // Without counting, a colliding pose has one cell (the first), as on the CPU.
      out[i].colliding_cells = count_cells ? answers[i].colliding_cells : (out[i].collides ? 1 : 0);
      out[i].first_cell = answers[i].first_cell;
    }
    return out;
  }

  DeviceScratch& s_;
  cudaStream_t stream_;
  /// checkRigidPoses: the stream of the poses' copies and the event of the latest one.
  std::unique_ptr<CudaStream> copies_;
  std::unique_ptr<CudaEvent> copied_;
};

}  // namespace
}  // namespace cuda

std::unique_ptr<CudaCollision> makeCudaCollision(DeviceScratch& scratch) {
  return std::make_unique<cuda::CudaCollisionImpl>(scratch);
}

}  // namespace fragg
