// The gain walk over the map's device layer view (one thread per viewpoint and ray).
#include "cuda_check.h"
#include "gain_kernels.h"

namespace fragg::cuda {

namespace {

__global__ void viewpointGainsKernel(GainKernelArgs a) {
  const uint64_t idx = uint64_t(blockIdx.x) * blockDim.x + threadIdx.x;
  const uint64_t total = uint64_t(a.viewpoints) * a.rays_per_viewpoint;
  double gain = 0.0;
  uint32_t vp = 0;
  if (idx < total) {
    vp = static_cast<uint32_t>(idx / a.rays_per_viewpoint);
    const uint32_t r = static_cast<uint32_t>(idx % a.rays_per_viewpoint);
    double dir[3];
    yawRotate(a.cos_yaw[vp], a.sin_yaw[vp], a.rays + 3 * r, dir);
    const double* origin = a.origins_v + 3 * vp;
    GainDda dda(origin, dir);
    const VoxelKey centre = dda.cell();
    const int64_t side = 2 * a.half + 1;
    unsigned long long* seen = a.seen + vp * a.words_per_viewpoint;
    BlockKey last{INT32_MIN, INT32_MIN, INT32_MIN};
    const Block* block = nullptr;
    for (double t = 0.0; t <= a.length_v; t = dda.next()) {
      const VoxelKey k = dda.cell();
      const BlockKey b = blockKeyOf(k);
      if (!(b == last)) {
        block = a.view.findBlock(b);
        last = b;
      }
      const Cell* cell = block ? &block->cells[cellIndexOf(k)] : nullptr;
      const CellState s = cell ? a.model.state(*cell) : CellState::kUnknown;
      if (s == CellState::kOccupied) break;
      if (s != CellState::kUnknown) continue;
      const int64_t lx = k.x - centre.x + a.half, ly = k.y - centre.y + a.half,
                    lz = k.z - centre.z + a.half;
      if (lx < 0 || ly < 0 || lz < 0 || lx >= side || ly >= side || lz >= side) continue;
      const uint64_t bit = uint64_t((lz * side + ly) * side + lx);
      const unsigned long long mask = 1ULL << (bit & 63);
      if (atomicOr(&seen[bit >> 6], mask) & mask) continue;
      gain += cellGainBits(a.model, cell);
    }
  }
  // Rays of one viewpoint are consecutive: sum within the warp where all lanes share it.
  const uint32_t first_vp = __shfl_sync(0xffffffffu, vp, 0);
  const bool shared = __all_sync(0xffffffffu, vp == first_vp);
  if (shared) {
    for (int offset = 16; offset > 0; offset /= 2)
      gain += __shfl_down_sync(0xffffffffu, gain, offset);
    if ((threadIdx.x & 31) == 0 && gain != 0.0) atomicAdd(&a.gains[vp], gain);
  } else if (idx < total && gain != 0.0) {
    atomicAdd(&a.gains[vp], gain);
  }
}

}  // namespace

void launchViewpointGains(const GainKernelArgs& args, cudaStream_t stream) {
  const uint64_t total = uint64_t(args.viewpoints) * args.rays_per_viewpoint;
  if (total == 0) return;
  constexpr int kThreads = 128;
  const uint64_t grid = (total + kThreads - 1) / kThreads;
  viewpointGainsKernel<<<static_cast<unsigned>(grid), kThreads, 0, stream>>>(args);
  FRAGG_CUDA_CHECK(cudaGetLastError());
}

}  // namespace fragg::cuda
