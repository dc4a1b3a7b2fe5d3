// Collision kernels: primitives one thread a pose, meshes one thread a candidate cell. The cell
// tests are the FRAGG_HD functions the CPU checker calls (internal/collision_pose.h,
// geometry/cube_overlap.h, geometry/bvh_traversal.h), on the same values.
#include <cfloat>
#include <cmath>

#include "collision_kernels.h"
#include "cuda_check.h"
#include "fragg_map/geometry/bvh_traversal.h"

namespace fragg::cuda {
namespace {

constexpr int kThreads = 128;
constexpr int kRangeThreads = 256;

// The obstacle cells of a pose's range in scan order, the exact test, stopping at the first
// collision unless count_cells (as the CPU checker's checkPrimitive).
__device__ CollisionAnswer checkPrimitivePose(const ObstacleMasksView& masks,
                                              const PrimitivePose& p, double resolution_m,
                                              double half_m, bool count_cells) {
  CollisionAnswer a;
  forEachObstacleCell(masks, p.lo, p.hi, [&](const VoxelKey& k) {
    if (!primitiveOverlapsCell(p, cellCentre(k, resolution_m), half_m)) return false;
    if (!a.collides) a.first_cell = k;
    a.collides = true;
    ++a.colliding_cells;
    return !count_cells;
  });
  return a;
}

// A pose's answer as each checker path stores it.
__device__ void store(const CollisionAnswer& a, DeviceAnswer* out) {
  *out = DeviceAnswer{a.collides ? 1u : 0u, UINT32_MAX, a.colliding_cells, a.first_cell};
}
__device__ void store(const CollisionAnswer& a, CollisionAnswer* out) { *out = a; }

template <class Answer>
__global__ void primitiveKernel(ObstacleMasksView masks, const PrimitivePose* poses, uint32_t n,
                                double resolution_m, double half_m, bool count_cells,
                                Answer* answers) {
  const uint32_t i = blockIdx.x * blockDim.x + threadIdx.x;
  if (i >= n) return;
  store(checkPrimitivePose(masks, poses[i], resolution_m, half_m, count_cells), &answers[i]);
}

// Pose first + i of the batch (poses[i]) as the host would prepare it. A pose whose cells leave
// the key range gets an empty cell range (lo > hi: nothing to visit) and is reported.
__global__ void preparePosesKernel(const RigidPose* poses, uint32_t first, uint32_t count,
                                   PrimitiveShape shape, PrimitivePose* prepared,
                                   uint32_t* first_bad) {
  const uint32_t i = blockIdx.x * blockDim.x + threadIdx.x;
  if (i >= count) return;
  PrimitivePose p;
  if (!preparePrimitivePose(shape, poses[i].R_map_shape, poses[i].t_map_shape, &p)) {
    atomicMin(first_bad, first + i);
    p.lo = VoxelKey{0, 0, 0};
    p.hi = VoxelKey{-1, -1, -1};
  }
  prepared[i] = p;
}

__device__ int32_t floorKey(double v) { return static_cast<int32_t>(floor(v)); }

__global__ void meshRangeKernel(DeviceMesh mesh, const MeshPose* poses, uint32_t n,
                                ObstacleMasksView masks, double resolution_m, double grow_m,
                                VoxelKey* lo, VoxelKey* hi, uint32_t* counts) {
  __shared__ double s_min[3][kRangeThreads], s_max[3][kRangeThreads];
  const uint32_t pose = blockIdx.x;
  if (pose >= n) return;
  const MeshPose& T = poses[pose];
  double mn[3] = {DBL_MAX, DBL_MAX, DBL_MAX}, mx[3] = {-DBL_MAX, -DBL_MAX, -DBL_MAX};
  for (uint32_t v = threadIdx.x; v < mesh.vertex_count; v += blockDim.x) {
    const Eigen::Vector3d p =
        transformPoint(T.R_map_shape, T.t_map_shape, mesh.vertices_m[v].cast<double>());
    for (int a = 0; a < 3; ++a) {
      mn[a] = fmin(mn[a], p[a]);
      mx[a] = fmax(mx[a], p[a]);
    }
  }
  for (int a = 0; a < 3; ++a) {
    s_min[a][threadIdx.x] = mn[a];
    s_max[a][threadIdx.x] = mx[a];
  }
  __syncthreads();
  for (int stride = blockDim.x / 2; stride > 0; stride /= 2) {
    if (threadIdx.x < stride)
      for (int a = 0; a < 3; ++a) {
        s_min[a][threadIdx.x] = fmin(s_min[a][threadIdx.x], s_min[a][threadIdx.x + stride]);
        s_max[a][threadIdx.x] = fmax(s_max[a][threadIdx.x], s_max[a][threadIdx.x + stride]);
      }
    __syncthreads();
  }
  if (threadIdx.x != 0) return;
  // As Map::keyOf: (p / resolution), floored.
  const VoxelKey l{floorKey((s_min[0][0] - grow_m) / resolution_m),
                   floorKey((s_min[1][0] - grow_m) / resolution_m),
                   floorKey((s_min[2][0] - grow_m) / resolution_m)};
  const VoxelKey h{floorKey((s_max[0][0] + grow_m) / resolution_m),
                   floorKey((s_max[1][0] + grow_m) / resolution_m),
                   floorKey((s_max[2][0] + grow_m) / resolution_m)};
  lo[pose] = l;
  hi[pose] = h;
  uint32_t count = 0;
  forEachObstacleCell(masks, l, h, [&](const VoxelKey&) {
    ++count;
    return false;
  });
  counts[pose] = count;
}

__global__ void meshCandidateKernel(ObstacleMasksView masks, const VoxelKey* lo, const VoxelKey* hi,
                                    const uint64_t* offsets, uint32_t n, VoxelKey* cells,
                                    uint32_t* pose_of_cell) {
  const uint32_t pose = blockIdx.x * blockDim.x + threadIdx.x;
  if (pose >= n) return;
  uint64_t at = offsets[pose];
  forEachObstacleCell(masks, lo[pose], hi[pose], [&](const VoxelKey& k) {
    cells[at] = k;
    pose_of_cell[at] = pose;
    ++at;
    return false;
  });
}

// Squared distance from p to the box [lo, hi] (float box, double arithmetic).
__device__ double boxDistanceSq(const Eigen::Vector3f& lo, const Eigen::Vector3f& hi,
                                const Eigen::Vector3d& p) {
  double d_sq = 0.0;
  for (int a = 0; a < 3; ++a) {
    const double below = static_cast<double>(lo[a]) - p[a];
    const double above = p[a] - static_cast<double>(hi[a]);
    const double d = fmax(0.0, fmax(below, above));
    d_sq += d * d;
  }
  return d_sq;
}

// Whether a triangle of the mesh meets the cube centre +- half_m: BVH nodes culled by the
// cube's circumscribed sphere in the shape frame (a superset: the exact test decides).
__device__ bool meshCutsCell(const DeviceMesh& mesh, const MeshPose& T,
                             const Eigen::Vector3d& centre, double half_m) {
  const Eigen::Vector3d p_shape = transformPoint(T.R_shape_map, T.t_shape_map, centre);
  const double reach = 1.7320508075688772 * half_m * (1.0 + 1e-9) + 1e-9;
  const double reach_sq = reach * reach;
  uint32_t stack[geometry::kBvhStackSize];
  int top = 0;
  stack[top++] = 0;
  while (top > 0) {
    const uint32_t index = stack[--top];
    const geometry::MeshBvh::Node& node = mesh.nodes[index];
    if (boxDistanceSq(node.lo, node.hi, p_shape) > reach_sq) continue;
    if (node.count == 0) {
      stack[top++] = node.first;
      stack[top++] = index + 1;
      continue;
    }
    for (uint32_t s = node.first; s < node.first + node.count; ++s) {
      const Eigen::Vector3i& t = mesh.slot_triangles[s];
      const Eigen::Vector3d a =
          transformPoint(T.R_map_shape, T.t_map_shape, mesh.vertices_m[t[0]].cast<double>());
      const Eigen::Vector3d b =
          transformPoint(T.R_map_shape, T.t_map_shape, mesh.vertices_m[t[1]].cast<double>());
      const Eigen::Vector3d c =
          transformPoint(T.R_map_shape, T.t_map_shape, mesh.vertices_m[t[2]].cast<double>());
      if (geometry::triangleCubeOverlap(a, b, c, centre, half_m)) return true;
    }
  }
  return false;
}

__global__ void meshTestKernel(DeviceMesh mesh, MeshCheck check, const MeshPose* poses,
                               const VoxelKey* cells, const uint32_t* pose_of_cell,
                               const uint64_t* offsets, uint64_t total, DeviceAnswer* answers,
                               uint32_t* overflow) {
  const uint64_t c = static_cast<uint64_t>(blockIdx.x) * blockDim.x + threadIdx.x;
  if (c >= total) return;
  const uint32_t pose = pose_of_cell[c];
  const uint32_t rank = static_cast<uint32_t>(c - offsets[pose]);
  // Without counting, a later cell cannot change the answer once an earlier one collided.
  if (!check.count_cells && *reinterpret_cast<volatile uint32_t*>(&answers[pose].first_rank) < rank)
    return;
  const MeshPose& T = poses[pose];
  const Eigen::Vector3d centre = cellCentre(cells[c], check.resolution_m);
  bool collides = meshCutsCell(mesh, T, centre, check.half_m);
  if (!collides && check.closed) {
    bool too_many = false;
    const Eigen::Vector3f p = transformPoint(T.R_shape_map, T.t_shape_map, centre).cast<float>();
    collides = geometry::bvhInside(mesh.nodes, mesh.tris, mesh.solid_of_slot, p, mesh.inside_dir,
                                   &too_many);
    if (too_many) atomicOr(overflow, 1u);
  }
  if (!collides) return;
  answers[pose].collides = 1;
  atomicAdd(&answers[pose].colliding_cells, 1ull);
  atomicMin(&answers[pose].first_rank, rank);
}

__global__ void meshFirstCellKernel(const VoxelKey* cells, const uint64_t* offsets, uint32_t n,
                                    DeviceAnswer* answers) {
  const uint32_t pose = blockIdx.x * blockDim.x + threadIdx.x;
  if (pose >= n || !answers[pose].collides) return;
  answers[pose].first_cell = cells[offsets[pose] + answers[pose].first_rank];
}

unsigned gridFor(uint64_t n) { return static_cast<unsigned>((n + kThreads - 1) / kThreads); }

}  // namespace

void launchPrimitiveCheck(const ObstacleMasksView& masks, const PrimitivePose* poses, uint32_t n,
                          double resolution_m, double half_m, bool count_cells,
                          DeviceAnswer* answers, cudaStream_t stream) {
  if (n == 0) return;
  primitiveKernel<<<gridFor(n), kThreads, 0, stream>>>(masks, poses, n, resolution_m, half_m,
                                                       count_cells, answers);
  FRAGG_CUDA_CHECK_LAUNCH("primitiveKernel");
}

void launchRigidPoseCheck(const ObstacleMasksView& masks, const RigidPose* poses, uint32_t first,
                          uint32_t count, const PrimitiveShape& shape, double half_m,
                          bool count_cells, PrimitivePose* prepared, CollisionAnswer* answers,
                          uint32_t* first_bad, cudaStream_t stream) {
  if (count == 0) return;
  preparePosesKernel<<<gridFor(count), kThreads, 0, stream>>>(poses, first, count, shape, prepared,
                                                              first_bad);
  FRAGG_CUDA_CHECK_LAUNCH("preparePosesKernel");
  primitiveKernel<<<gridFor(count), kThreads, 0, stream>>>(
      masks, prepared, count, shape.resolution_m, half_m, count_cells, answers);
  FRAGG_CUDA_CHECK_LAUNCH("primitiveKernel");
}

void launchMeshRanges(const DeviceMesh& mesh, const MeshPose* poses, uint32_t n,
                      const ObstacleMasksView& masks, double resolution_m, double grow_m,
                      VoxelKey* lo, VoxelKey* hi, uint32_t* counts, cudaStream_t stream) {
  if (n == 0) return;
  meshRangeKernel<<<n, kRangeThreads, 0, stream>>>(mesh, poses, n, masks, resolution_m, grow_m, lo,
                                                   hi, counts);
  FRAGG_CUDA_CHECK_LAUNCH("meshRangeKernel");
}

void launchMeshCandidates(const ObstacleMasksView& masks, const VoxelKey* lo, const VoxelKey* hi,
                          const uint64_t* offsets, uint32_t n, VoxelKey* cells,
                          uint32_t* pose_of_cell, cudaStream_t stream) {
  if (n == 0) return;
  meshCandidateKernel<<<gridFor(n), kThreads, 0, stream>>>(masks, lo, hi, offsets, n, cells,
                                                           pose_of_cell);
  FRAGG_CUDA_CHECK_LAUNCH("meshCandidateKernel");
}

void launchMeshTest(const DeviceMesh& mesh, const MeshCheck& check, const MeshPose* poses,
                    const VoxelKey* cells, const uint32_t* pose_of_cell, const uint64_t* offsets,
                    uint64_t total, DeviceAnswer* answers, uint32_t* overflow,
                    cudaStream_t stream) {
  if (total == 0) return;
  meshTestKernel<<<gridFor(total), kThreads, 0, stream>>>(mesh, check, poses, cells, pose_of_cell,
                                                          offsets, total, answers, overflow);
  FRAGG_CUDA_CHECK_LAUNCH("meshTestKernel");
}

void launchMeshFirstCells(const VoxelKey* cells, const uint64_t* offsets, uint32_t n,
                          DeviceAnswer* answers, cudaStream_t stream) {
  if (n == 0) return;
  meshFirstCellKernel<<<gridFor(n), kThreads, 0, stream>>>(cells, offsets, n, answers);
  FRAGG_CUDA_CHECK_LAUNCH("meshFirstCellKernel");
}

}  // namespace fragg::cuda
