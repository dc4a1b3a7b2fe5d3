// The auto sensor model's statistics on the device: each thread gathers its points with the
// host's addAutoSensorPoint(), a thread block merges its threads' statistics (warp shuffles,
// then shared memory), and one thread merges the block's into the accumulators with atomics.
// Every merge is exact in any order, so the result has the host's bits.
#include "auto_stats_accum.h"
#include "cuda_check.h"
#include "kernels.h"
#include "warp_reduce.cuh"

namespace fragg::cuda {

namespace {
constexpr unsigned kThreads = 256;
constexpr unsigned kMaxBlocks = 1024;

__device__ AutoSensorStats shuffleXor(const AutoSensorStats& s, int offset) {
  AutoSensorStats o;
  o.max_dist_m = __shfl_xor_sync(kFullMask, s.max_dist_m, offset);
  o.sin_min = __shfl_xor_sync(kFullMask, s.sin_min, offset);
  o.sin_max = __shfl_xor_sync(kFullMask, s.sin_max, offset);
  for (int i = 0; i < 3; ++i)
    o.dir_sum_fx[i] = __shfl_xor_sync(kFullMask, (long long)s.dir_sum_fx[i], offset);
  o.valid = __shfl_xor_sync(kFullMask, (unsigned long long)s.valid, offset);
  for (int k = 0; k < 6; ++k) {
    o.fit[k].fits = __shfl_xor_sync(kFullMask, s.fit[k].fits, offset);
    o.fit[k].tan_h = __shfl_xor_sync(kFullMask, s.fit[k].tan_h, offset);
    o.fit[k].tan_v = __shfl_xor_sync(kFullMask, s.fit[k].tan_v, offset);
  }
  return o;
}

__device__ void mergeInto(AutoStatsAccum* a, const AutoSensorStats& s) {
  atomicMax(&a->max_dist_key, orderedKey(s.max_dist_m));
  atomicMin(&a->sin_min_key, orderedKey(s.sin_min));
  atomicMax(&a->sin_max_key, orderedKey(s.sin_max));
  for (int i = 0; i < 3; ++i)
    atomicAdd(&a->dir_sum[i], static_cast<unsigned long long>(s.dir_sum_fx[i]));
  atomicAdd(&a->valid, static_cast<unsigned long long>(s.valid));
  for (int k = 0; k < 6; ++k) {
    if (!s.fit[k].fits) {
      atomicAnd(&a->fits[k], 0);
      continue;
    }
    atomicMax(&a->tan_h_key[k], orderedKey(s.fit[k].tan_h));
    atomicMax(&a->tan_v_key[k], orderedKey(s.fit[k].tan_v));
  }
}

__global__ void autoSensorStatsKernel(const float* __restrict__ points_S, uint32_t n,
                                      SensorAxisTable axes, AutoStatsAccum* out) {
  // Raw storage: a __shared__ array may not have a constructor.
  __shared__ alignas(AutoSensorStats) unsigned char raw[sizeof(AutoSensorStats) * (kThreads / 32)];
  AutoSensorStats* warp_stats = reinterpret_cast<AutoSensorStats*>(raw);
  AutoSensorStats s;
  for (uint32_t i = blockIdx.x * blockDim.x + threadIdx.x; i < n; i += gridDim.x * blockDim.x)
    addAutoSensorPoint(points_S[3 * i], points_S[3 * i + 1], points_S[3 * i + 2], axes, s);
  for (int o = 16; o > 0; o >>= 1) s.merge(shuffleXor(s, o));
  const unsigned lane = threadIdx.x & 31, warp = threadIdx.x >> 5;
  if (lane == 0) warp_stats[warp] = s;
  __syncthreads();
  if (threadIdx.x != 0) return;
  for (unsigned w = 1; w < kThreads / 32; ++w) s.merge(warp_stats[w]);
  mergeInto(out, s);
}
}  // namespace

void launchAutoSensorStats(const float* points_S, uint32_t n, const SensorAxisTable& axes,
                           AutoStatsAccum* out, cudaStream_t stream) {
  if (n == 0) return;
  const unsigned blocks = blocksFor(n, kThreads) < kMaxBlocks ? blocksFor(n, kThreads) : kMaxBlocks;
  autoSensorStatsKernel<<<blocks, kThreads, 0, stream>>>(points_S, n, axes, out);
  FRAGG_CUDA_CHECK_LAUNCH("autoSensorStatsKernel");
}

}  // namespace fragg::cuda
