#include "state_bits.h"

#include <algorithm>

#include "cuda_stream.h"

namespace fragg::cuda {

namespace {

constexpr int kWordsPerBlock = 16;
/// Keys per round: each round makes its blocks resident before reading them.
constexpr size_t kRoundKeys = size_t(1) << 16;

/// The host loop, for a block the cache could not keep resident through its round.
void hostBits(const OccupancyModel& model, const Block& block, uint64_t* out) {
  for (int w = 0; w < 8; ++w) {
    uint64_t free_bits = 0, unknown_bits = 0;
    for (int b = 0; b < 64; ++b) {
      const CellState s = model.state(block.cells[w * 64 + b]);
      free_bits |= uint64_t(s == CellState::kFree) << b;
      unknown_bits |= uint64_t(s == CellState::kUnknown) << b;
    }
    out[w] = free_bits;
    out[8 + w] = unknown_bits;
  }
}

}  // namespace

void CellStateBits::compute(DeviceBlockCache& cache, const std::vector<BlockKey>& keys,
                            const OccupancyModel& model, BlockMap& blocks, uint64_t* out) {
  for (size_t first = 0; first < keys.size(); first += kRoundKeys) {
    const size_t n = std::min(kRoundKeys, keys.size() - first);
    const std::vector<BlockKey> round(keys.begin() + first, keys.begin() + first + n);
    cache.ensureResident(round, blocks);
    slots_host_.reserve(n);
    std::vector<size_t> on_host;  // existing blocks evicted again within the round
    for (size_t i = 0; i < n; ++i) {
      const BlockIndex b = blocks.find(round[i]);
      const int32_t slot = b == kNoBlock ? -1 : cache.slotOf(b);
      slots_host_[i] = slot;
      if (b != kNoBlock && slot < 0) on_host.push_back(i);
    }
    slots_.reserve(n);
    bits_.reserve(n * kWordsPerBlock);
    copyToDevice(slots_.get(), slots_host_.get(), n, stream_);
    launchCellStateBits(cache.arrays().cells, slots_.get(), static_cast<uint32_t>(n), model,
                        bits_.get(), stream_);
    uint64_t* dst = out + first * kWordsPerBlock;
    copyToHost(dst, bits_.get(), n * kWordsPerBlock, stream_);
    FRAGG_CUDA_CHECK(cudaStreamSynchronize(stream_));
    for (size_t i : on_host)
      hostBits(model, blocks.block(blocks.find(round[i])), dst + i * kWordsPerBlock);
  }
}

}  // namespace fragg::cuda
