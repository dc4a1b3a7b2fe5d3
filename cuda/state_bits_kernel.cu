// One warp per block: lane l reads cells l, l + 32, ... (coalesced), the warp's ballots are
// the bitmaps.
#include "cuda_check.h"
#include "state_bits_kernel.h"

namespace fragg::cuda {

namespace {

__global__ void cellStateBitsKernel(const Block* slot_cells, const int32_t* slots, uint32_t n,
                                    OccupancyModel model, uint64_t* out) {
  const uint32_t warp = (blockIdx.x * blockDim.x + threadIdx.x) / 32;
  const int lane = threadIdx.x & 31;
  if (warp >= n) return;
  const int32_t slot = slots[warp];
  uint64_t* dst = out + size_t(warp) * 16;
  if (slot < 0) {
    if (lane < 8)
      dst[lane] = 0;
    else if (lane < 16)
      dst[lane] = ~0ULL;
    return;
  }
  const Cell* cells = slot_cells[slot].cells;
  for (int w = 0; w < 8; ++w) {
    uint64_t free_bits = 0, unknown_bits = 0;
    for (int half = 0; half < 2; ++half) {
      const CellState s = model.state(cells[w * 64 + half * 32 + lane]);
      const uint32_t f = __ballot_sync(0xffffffffu, s == CellState::kFree);
      const uint32_t u = __ballot_sync(0xffffffffu, s == CellState::kUnknown);
      free_bits |= uint64_t(f) << (32 * half);
      unknown_bits |= uint64_t(u) << (32 * half);
    }
    if (lane == 0) {
      dst[w] = free_bits;
      dst[8 + w] = unknown_bits;
    }
  }
}

}  // namespace

void launchCellStateBits(const Block* slot_cells, const int32_t* slots, uint32_t n,
                         const OccupancyModel& model, uint64_t* out, cudaStream_t stream) {
  if (n == 0) return;
  constexpr int kThreads = 256;  // 8 blocks of the map per thread block
  const uint32_t grid = (n * 32 + kThreads - 1) / kThreads;
  cellStateBitsKernel<<<grid, kThreads, 0, stream>>>(slot_cells, slots, n, model, out);
  FRAGG_CUDA_CHECK(cudaGetLastError());
}

}  // namespace fragg::cuda
