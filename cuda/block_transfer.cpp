#include "block_transfer.h"

#include <omp.h>

#include <algorithm>
#include <cstring>

#include "kernels.h"

namespace fragg::cuda {

void BlockTransfer::reserve(size_t n, bool staging) {
  block_ptrs_.reserve(n);
  slots_.reserve(n);
  keys_.reserve(n);
  masks_.reserve(n);  // the host masks are not pinned: staged either way
  if (staging) staging_.reserve(n);
}

void BlockTransfer::upload(const SlotArrays& pool, const std::vector<BlockIndex>& host_blocks,
                           const std::vector<int32_t>& slots, const BlockMap& blocks,
                           uint32_t scan) {
  for (size_t begin = 0; begin < host_blocks.size(); begin += kBatch) {
    const size_t n = std::min(kBatch, host_blocks.size() - begin);
    reserve(n, /*staging=*/!direct_);
#pragma omp parallel for schedule(static) num_threads(threads_)
    for (long j = 0; j < static_cast<long>(n); ++j) {
      const BlockIndex i = host_blocks[begin + j];
      slots_[j] = slots[begin + j];
      keys_[j] = blocks.meta(i).key;
      masks_[j] = blocks.masks(i);
      if (direct_) {
        block_ptrs_[j] = const_cast<Block*>(&blocks.block(i));
      } else {
        std::memcpy(&staging_[j], &blocks.block(i), sizeof(Block));
        block_ptrs_[j] = staging_.device() + j;
      }
    }
    if (!direct_) staging_.toDevice(n, stream_);
    block_ptrs_.toDevice(n, stream_);
    slots_.toDevice(n, stream_);
    keys_.toDevice(n, stream_);
    masks_.toDevice(n, stream_);
    launchUpload(pool, block_ptrs_.device(), masks_.device(), slots_.device(), keys_.device(),
                 uint32_t(n), scan, stream_);
    FRAGG_CUDA_CHECK(cudaStreamSynchronize(stream_));  // the pinned lists are reused next batch
  }
}

void BlockTransfer::writeBack(
    const SlotArrays& pool, const std::vector<int32_t>& slots, BlockMap& blocks,
    const std::function<BlockIndex(int32_t slot, const BlockKey& key)>& host_block_of) {
  for (size_t begin = 0; begin < slots.size(); begin += kBatch) {
    const size_t n = std::min(kBatch, slots.size() - begin);
    reserve(n, /*staging=*/!direct_);
    stamps_.reserve(3 * n);
    for (size_t j = 0; j < n; ++j) slots_[j] = slots[begin + j];
    slots_.toDevice(n, stream_);
    std::vector<BlockIndex> target(n);
    if (direct_) {
      // Pinned host blocks the device addresses: the download kernel writes each block in
      // place (no staging, no host copy). Their keys first, so that the host blocks of slots
      // made on the device exist (in order: creating host blocks is not thread-safe).
      launchGatherKeys(pool, slots_.device(), uint32_t(n), keys_.device(), stream_);
      keys_.toHost(n, stream_);
      FRAGG_CUDA_CHECK(cudaStreamSynchronize(stream_));
      for (size_t j = 0; j < n; ++j) target[j] = host_block_of(slots_[j], keys_[j]);
      for (size_t j = 0; j < n; ++j) block_ptrs_[j] = &blocks.block(target[j]);
    } else {
      for (size_t j = 0; j < n; ++j) block_ptrs_[j] = staging_.device() + j;
    }
    block_ptrs_.toDevice(n, stream_);
    launchDownload(pool, block_ptrs_.device(), masks_.device(), slots_.device(), uint32_t(n),
                   keys_.device(), stamps_.device(), stream_);
    if (!direct_) staging_.toHost(n, stream_);
    masks_.toHost(n, stream_);
    if (!direct_) keys_.toHost(n, stream_);  // direct: gathered before the copy
    stamps_.toHost(3 * n, stream_);
    FRAGG_CUDA_CHECK(cudaStreamSynchronize(stream_));
    if (!direct_) {
      // Targets first, in order (creating host blocks is not thread-safe), then the copies.
      for (size_t j = 0; j < n; ++j) target[j] = host_block_of(slots_[j], keys_[j]);
    }
#pragma omp parallel for schedule(static) num_threads(threads_) if (!direct_ || n > 4096)
    for (long j = 0; j < static_cast<long>(n); ++j) {
      if (!direct_) std::memcpy(&blocks.block(target[j]), &staging_[j], sizeof(Block));
      blocks.masks(target[j]) = masks_[j];
      BlockMeta& m = blocks.meta(target[j]);
      m.changed_at = std::max(m.changed_at, stamps_[j]);
      m.occupied_at = std::max(m.occupied_at, stamps_[n + j]);
      // The device keeps no state stamp: any change may have changed a state (never missed,
      // sometimes more than needed).
      m.state_at = std::max(m.state_at, stamps_[j]);
    }
    // The change log appends: one thread.
    for (size_t j = 0; j < n; ++j) blocks.noteMasksChanged(target[j], stamps_[2 * n + j]);
  }
}

}  // namespace fragg::cuda
