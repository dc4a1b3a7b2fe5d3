// The CUDA collision checker: uploads the batch's obstacle masks (built by the planning tier
// from the map's blocks) and poses, runs the collision kernels, reads the answers back.
#include "fragg_map/internal/cuda_collision.h"

#include <algorithm>
#include <memory>
#include <vector>

#include "collision_kernels.h"
#include "cuda_array.h"
#include "cuda_check.h"
#include "cuda_stream.h"
#include "fragg_map/errors.h"

namespace fragg {
namespace cuda {
namespace {

class CudaCollisionImpl final : public CudaCollision {
 public:
  explicit CudaCollisionImpl(int device) { FRAGG_CUDA_CHECK(cudaSetDevice(device)); }

  std::vector<CollisionAnswer> checkPrimitives(const ObstacleMasksHost& masks,
                                               const std::vector<PrimitivePose>& poses,
                                               double resolution_m, double half_m,
                                               bool count_cells) override {
    const uint32_t n = static_cast<uint32_t>(poses.size());
    const ObstacleMasksView view = uploadMasks(masks);
    primitive_poses_.reserve(n);
    answers_.reserve(n);
    copyToDevice(primitive_poses_.get(), poses.data(), n, stream_.get());
    launchPrimitiveCheck(view, primitive_poses_.get(), n, resolution_m, half_m, count_cells,
                         answers_.get(), stream_.get());
    return download(n, count_cells);
  }

  std::vector<CollisionAnswer> checkMesh(const ObstacleMasksHost& masks,
                                         const std::vector<MeshPose>& poses,
                                         const MeshCheck& check) override {
    const uint32_t n = static_cast<uint32_t>(poses.size());
    const ObstacleMasksView view = uploadMasks(masks);
    const DeviceMesh mesh = uploadMesh(*check.bvh);
    mesh_poses_.reserve(n);
    lo_.reserve(n);
    hi_.reserve(n);
    counts_.reserve(n);
    offsets_.reserve(n + 1);
    answers_.reserve(n);
    copyToDevice(mesh_poses_.get(), poses.data(), n, stream_.get());
    launchMeshRanges(mesh, mesh_poses_.get(), n, view, check.resolution_m, check.grow_m, lo_.get(),
                     hi_.get(), counts_.get(), stream_.get());
    std::vector<uint32_t> counts(n);
    copyToHost(counts.data(), counts_.get(), n, stream_.get());
    stream_.sync();
    std::vector<uint64_t> offsets(n + 1, 0);
    for (uint32_t i = 0; i < n; ++i) offsets[i + 1] = offsets[i] + counts[i];
    const uint64_t total = offsets[n];
    copyToDevice(offsets_.get(), offsets.data(), n + 1, stream_.get());
    cells_.reserve(std::max<uint64_t>(total, 1));
    pose_of_cell_.reserve(std::max<uint64_t>(total, 1));
    launchMeshCandidates(view, lo_.get(), hi_.get(), offsets_.get(), n, cells_.get(),
                         pose_of_cell_.get(), stream_.get());
    std::vector<DeviceAnswer> init(n, DeviceAnswer{0, UINT32_MAX, 0, VoxelKey{}});
    copyToDevice(answers_.get(), init.data(), n, stream_.get());
    overflow_.reserve(1);
    FRAGG_CUDA_CHECK(cudaMemsetAsync(overflow_.get(), 0, sizeof(uint32_t), stream_.get()));
    launchMeshTest(mesh, check, mesh_poses_.get(), cells_.get(), pose_of_cell_.get(),
                   offsets_.get(), total, answers_.get(), overflow_.get(), stream_.get());
    launchMeshFirstCells(cells_.get(), offsets_.get(), n, answers_.get(), stream_.get());
    uint32_t overflow = 0;
    copyToHost(&overflow, overflow_.get(), 1, stream_.get());
    std::vector<CollisionAnswer> out = download(n, check.count_cells);
    if (overflow) throw InvalidArgument("inside test: more than 32 solids above one point");
    return out;
  }

 private:
  ObstacleMasksView uploadMasks(const ObstacleMasksHost& m) {
    keys_.reserve(m.keys->size());
    slots_.reserve(m.slots->size());
    masks_.reserve(std::max<size_t>(m.masks->size(), 1));
    copyToDevice(keys_.get(), m.keys->data(), m.keys->size(), stream_.get());
    copyToDevice(slots_.get(), m.slots->data(), m.slots->size(), stream_.get());
    copyToDevice(masks_.get(), m.masks->data(), m.masks->size(), stream_.get());
    ObstacleMasksView v;
    v.keys = keys_.get();
    v.slots = slots_.get();
    v.masks = masks_.get();
    v.capacity_mask = static_cast<uint32_t>(m.keys->size() - 1);
    v.default_word = m.default_word;
    return v;
  }

  DeviceMesh uploadMesh(const geometry::MeshBvh& bvh) {
    const geometry::TriangleMesh& mesh = bvh.mesh();
    std::vector<Eigen::Vector3i> slot_triangles(bvh.leafOrder().size());
    for (size_t s = 0; s < slot_triangles.size(); ++s)
      slot_triangles[s] = mesh.triangles[bvh.leafOrder()[s]];
    nodes_.reserve(bvh.nodes().size());
    tris_.reserve(bvh.leafTriangles().size());
    solids_.reserve(bvh.leafSolids().size());
    vertices_.reserve(mesh.vertices_m.size());
    slot_triangles_.reserve(slot_triangles.size());
    copyToDevice(nodes_.get(), bvh.nodes().data(), bvh.nodes().size(), stream_.get());
    copyToDevice(tris_.get(), bvh.leafTriangles().data(), bvh.leafTriangles().size(),
                 stream_.get());
    copyToDevice(solids_.get(), bvh.leafSolids().data(), bvh.leafSolids().size(), stream_.get());
    copyToDevice(vertices_.get(), mesh.vertices_m.data(), mesh.vertices_m.size(), stream_.get());
    copyToDevice(slot_triangles_.get(), slot_triangles.data(), slot_triangles.size(),
                 stream_.get());
    // The host vector must outlive the asynchronous copy.
    stream_.sync();
    DeviceMesh d;
    d.nodes = nodes_.get();
    d.tris = tris_.get();
    d.solid_of_slot = solids_.get();
    d.vertices_m = vertices_.get();
    d.slot_triangles = slot_triangles_.get();
    d.vertex_count = static_cast<uint32_t>(mesh.vertices_m.size());
    d.inside_dir = geometry::MeshBvh::insideRayDirection();
    return d;
  }

  std::vector<CollisionAnswer> download(uint32_t n, bool count_cells) {
    std::vector<DeviceAnswer> answers(n);
    copyToHost(answers.data(), answers_.get(), n, stream_.get());
    stream_.sync();
    std::vector<CollisionAnswer> out(n);
    for (uint32_t i = 0; i < n; ++i) {
      out[i].collides = answers[i].collides != 0;
      // Without counting, a colliding pose has one cell (the first), as on the CPU.
      out[i].colliding_cells = count_cells ? answers[i].colliding_cells : (out[i].collides ? 1 : 0);
      out[i].first_cell = answers[i].first_cell;
    }
    return out;
  }

  CudaStream stream_;
  DeviceArray<BlockKey> keys_;
  DeviceArray<int32_t> slots_;
  DeviceArray<uint64_t> masks_;
  DeviceArray<PrimitivePose> primitive_poses_;
  DeviceArray<MeshPose> mesh_poses_;
  DeviceArray<DeviceAnswer> answers_;
  DeviceArray<VoxelKey> lo_, hi_, cells_;
  DeviceArray<uint32_t> counts_, pose_of_cell_, overflow_;
  DeviceArray<uint64_t> offsets_;
  DeviceArray<geometry::MeshBvh::Node> nodes_;
  DeviceArray<geometry::MeshBvh::Tri> tris_;
  DeviceArray<int32_t> solids_;
  DeviceArray<Eigen::Vector3f> vertices_;
  DeviceArray<Eigen::Vector3i> slot_triangles_;
};

}  // namespace
}  // namespace cuda

std::unique_ptr<CudaCollision> makeCudaCollision(int device) {
  return std::make_unique<cuda::CudaCollisionImpl>(device);
}

}  // namespace fragg
