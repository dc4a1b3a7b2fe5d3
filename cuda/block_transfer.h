// Batched block copies between the host map and the device pool: uploads and write-backs,
// straight from and into pinned host blocks the device addresses (direct), else through
// pinned staging, each in batches of kBatch blocks with one kernel per batch.
#pragma once

#include <functional>
#include <vector>

#include "device_types.h"
#include "fragg_map/block_map.h"
#include "fragg_map/internal/thread_count.h"
#include "mirrored_buffer.h"

namespace fragg::cuda {

class BlockTransfer {
 public:
  /// Blocks moved per batch (32 MiB of staging where the host blocks are not direct).
  static constexpr size_t kBatch = 16384;

  /// `direct`: host blocks are pinned and device-addressable, so the upload kernel reads
  /// them in place and the download kernel writes them in place (no staging is allocated);
  /// `host_threads`: threads of the host-side copies (0: every core).
  BlockTransfer(cudaStream_t stream, bool direct, int host_threads)
      : stream_(stream), direct_(direct), threads_(threadCount(host_threads)) {}

  /// Copies host block host_blocks[j] and its state masks into slot slots[j] (key set, dirty
  /// cleared, last_used = scan).
  void upload(const SlotArrays& pool, const std::vector<BlockIndex>& host_blocks,
              const std::vector<int32_t>& slots, const BlockMap& blocks, uint32_t scan);
  /// Copies each slot back to the host block `host_block_of(slot, key)` names (called in
  /// order, on this thread: it may create the block; direct, before the copy, which then
  /// lands in place), with its state masks, and its
  /// changed_at / occupied_at merged into the block's metadata (a newer masks_at through
  /// BlockMap::noteMasksChanged: the change log); clears the slots' dirty flags.
  void writeBack(const SlotArrays& pool, const std::vector<int32_t>& slots, BlockMap& blocks,
                 const std::function<BlockIndex(int32_t slot, const BlockKey& key)>& host_block_of);
  size_t deviceBytes() const { return staging_.deviceBytes() + masks_.deviceBytes(); }

 private:
  void reserve(size_t n, bool staging);

  cudaStream_t stream_;
  bool direct_;
  int threads_;
  MirroredBuffer<Block> staging_;
  MirroredBuffer<BlockStateMasks> masks_;  ///< the staged blocks' masks (both ways)
  MirroredBuffer<Block*> block_ptrs_;      ///< device-visible source / target of each block
  MirroredBuffer<int32_t> slots_;
  MirroredBuffer<BlockKey> keys_;
  MirroredBuffer<uint64_t> stamps_;  ///< changed_at of each block, then occupied_at, masks_at
};

}  // namespace fragg::cuda
