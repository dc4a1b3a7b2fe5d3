// Transform and filter on the device: the same prepareRay() as the CPU backend.
#include <climits>

#include "cuda_check.h"
#include "fragg_map/raycast.h"
#include "kernels.h"
#include "warp_reduce.cuh"

namespace fragg::cuda {

namespace {
constexpr unsigned kThreads = 256;

__global__ void prepareKernel(const float* __restrict__ points_S,
                              const uint8_t* __restrict__ free_only_flags, uint32_t n,
                              RayPrepParams p, Frustum f, RayEnd* __restrict__ rays,
                              uint32_t* __restrict__ ray_points, ScanCounters* c) {
  const uint32_t i = blockIdx.x * blockDim.x + threadIdx.x;
  RayEnd ray{};
  RayPrep outcome = RayPrep::kInvalid;
  const bool valid = i < n;
  if (valid)
    outcome = prepareRay(p, f, points_S[3 * i], points_S[3 * i + 1], points_S[3 * i + 2],
                         free_only_flags != nullptr && free_only_flags[i] != 0, &ray);
  const bool keep = valid && (outcome == RayPrep::kHit || outcome == RayPrep::kFreeOnly);
  const unsigned lane = threadIdx.x & 31;

  // Compaction: one atomic a warp.
  const unsigned kept = __ballot_sync(kFullMask, keep);
  uint32_t base = 0;
  if (lane == 0 && kept) base = atomicAdd(&c->rays, __popc(kept));
  base = __shfl_sync(kFullMask, base, 0);
  if (keep) {
    const uint32_t r = base + __popc(kept & ((1u << lane) - 1u));
    rays[r] = ray;
    if (ray_points) ray_points[r] = i;
  }

  // Counters.
  const unsigned hits = __ballot_sync(kFullMask, valid && outcome == RayPrep::kHit);
  const unsigned free_only = __ballot_sync(kFullMask, valid && outcome == RayPrep::kFreeOnly);
  const unsigned invalid = __ballot_sync(kFullMask, valid && outcome == RayPrep::kInvalid);
  const unsigned too_close = __ballot_sync(kFullMask, valid && outcome == RayPrep::kTooClose);
  const unsigned outside = __ballot_sync(kFullMask, valid && outcome == RayPrep::kOutside);
  if (lane == 0) {
    if (hits) atomicAdd(&c->hits, __popc(hits));
    if (free_only) atomicAdd(&c->free_only, __popc(free_only));
    if (invalid) atomicAdd(&c->invalid, __popc(invalid));
    if (too_close) atomicAdd(&c->too_close, __popc(too_close));
    if (outside) atomicAdd(&c->outside, __popc(outside));
  }

  // Bounds of the kept rays' end cells.
  int lo[3], hi[3];
  for (int a = 0; a < 3; ++a) {
    const int v =
        keep ? rayEndCell(ray, a, p.octomap_keys, p.inv_res, static_cast<int>(p.ref_v[a])) : 0;
    lo[a] = warpMin(keep ? v : INT_MAX);
    hi[a] = warpMax(keep ? v : INT_MIN);
  }
  if (lane == 0 && kept) {
    for (int a = 0; a < 3; ++a) {
      atomicMin(&c->lo_v[a], lo[a]);
      atomicMax(&c->hi_v[a], hi[a]);
    }
  }
}
}  // namespace

void launchPrepare(const float* points_S, const uint8_t* free_only_flags, uint32_t n,
                   const RayPrepParams& p, const Frustum& f, RayEnd* rays, uint32_t* ray_points,
                   ScanCounters* counters, cudaStream_t stream) {
  if (n == 0) return;
  prepareKernel<<<blocksFor(n, kThreads), kThreads, 0, stream>>>(points_S, free_only_flags, n, p, f,
                                                                 rays, ray_points, counters);
  FRAGG_CUDA_CHECK_LAUNCH("prepareKernel");
}

}  // namespace fragg::cuda
