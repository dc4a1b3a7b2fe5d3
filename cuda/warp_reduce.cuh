// Warp-level helpers (sm_75 and later).
#pragma once

namespace fragg::cuda {

constexpr unsigned kFullMask = 0xffffffffu;

__device__ __forceinline__ int warpMin(int v) {
  for (int o = 16; o > 0; o >>= 1) v = min(v, __shfl_xor_sync(kFullMask, v, o));
  return v;
}
__device__ __forceinline__ int warpMax(int v) {
  for (int o = 16; o > 0; o >>= 1) v = max(v, __shfl_xor_sync(kFullMask, v, o));
  return v;
}
__device__ __forceinline__ unsigned long long warpSum(unsigned long long v) {
  for (int o = 16; o > 0; o >>= 1) v += __shfl_xor_sync(kFullMask, v, o);
  return v;
}

inline unsigned blocksFor(unsigned long long n, unsigned threads) {
  return static_cast<unsigned>((n + threads - 1) / threads);
}

}  // namespace fragg::cuda
