// The CUDA backend's block cache (DESIGN §3 step 2, §11): a device pool of slots holding the
// blocks scans and queries need, written back to the host map on demand (write-back cache);
// least recently visible slots are evicted first. The host map stays the map.
#pragma once

#include <cstdint>
#include <functional>
#include <vector>

#include "block_transfer.h"
#include "cuda_array.h"
#include "fragg_map/internal/backend.h"
#include "host_only_index.h"
#include "slot_pool.h"

namespace fragg::cuda {

class DeviceBlockCache : public BlockCache {
 public:
  /// `pool_max_bytes`: the pool's limit (0: half the free device memory); `direct_uploads`:
  /// host blocks are pinned and device-addressable; `host_threads`: threads of the host-side
  /// block copies (0: every core).
  DeviceBlockCache(cudaStream_t stream, size_t pool_max_bytes, bool direct_uploads,
                   int host_threads);

  // BlockCache.
  void ensureResident(const std::vector<BlockKey>& keys, BlockMap& blocks) override;
  void ensureResident(const BlockKey& lo, const BlockKey& hi, BlockMap& blocks) override;
  void sync(BlockMap& blocks) override;
  bool syncSome(BlockMap& blocks, size_t max_blocks) override;
  bool needsSync() const override { return any_dirty_; }
  size_t blocksNotInHostMap() const override {
    return static_cast<size_t>(pool_.table().deviceOnlyCount());
  }
  void invalidate(const BlockKey& lo, const BlockKey& hi, BlockMap& blocks) override;
  void invalidateAll(BlockMap& blocks) override;
  void forget(const std::vector<BlockIndex>& host_blocks, BlockMap& blocks) override;
  void added(const std::vector<BlockIndex>& host_blocks, const BlockMap& blocks) override;
  size_t deviceBytes() const override { return pool_.deviceBytes() + transfer_.deviceBytes(); }

  /// Grows an empty pool to `slots` (capped by the pool's limit).
  void reserve(int64_t slots);
  /// A new scan: slots it uses (uploads, culling, rays) are stamped with its number and kept
  /// by the evictions it causes. Returns the number.
  uint32_t beginScan() { return ++scan_; }
  uint32_t currentScan() const { return scan_; }

  /// Makes `want` slots free if it can, `need` or more in any case: grows the pool, else
  /// evicts least recently used slots (never one of the current scan). Returns the host
  /// blocks it evicted. Throws CudaOutOfMemory when fewer than `need` can be had.
  std::vector<BlockIndex> makeRoom(int32_t need, int32_t want, BlockMap& blocks);
  /// Uploads host blocks that have no slot (room must have been made).
  void upload(const std::vector<BlockIndex>& host_blocks, const BlockMap& blocks);
  /// Takes the slots the rays allocated (the device's free stack is down to `new_free_top`)
  /// as resident blocks that exist on the device only; returns how many.
  uint32_t adoptDeviceSlots(int32_t new_free_top);
  /// The device changed slots: sync() has work.
  void markDirty() { any_dirty_ = true; }
  /// Paging: the keys of the blocks this scan's rays marked (the first `touched` slots of the
  /// pool's touched list, as the last ray pass listed them; the blocks they created among
  /// them). Reads the touched list and the pool's keys back.
  std::vector<BlockKey> keysMarked(uint32_t touched);
  /// Calls fn(i) for every host block without a slot whose key lies in [lo, hi].
  void forEachHostOnlyIn(const BlockMap& blocks, const BlockKey& lo, const BlockKey& hi,
                         const std::function<void(BlockIndex)>& fn);

  SlotArrays arrays() const { return pool_.arrays(); }
  int32_t freeSlots() const { return pool_.table().freeCount(); }
  int32_t slotOf(BlockIndex block) const { return pool_.table().slotOf(block); }
  uint64_t uploadedCount() const { return uploaded_; }
  uint64_t evictedCount() const { return evicted_; }

 private:
  int32_t slotLimit() const;
  std::vector<BlockIndex> evict(int32_t n, BlockMap& blocks);
  /// Frees the slots (written back first when dirty); their host blocks become host-only.
  std::vector<BlockIndex> dropSlots(const std::vector<int32_t>& slots, BlockMap& blocks);
  void writeBack(const std::vector<int32_t>& slots, BlockMap& blocks);
  /// The pool's dirty flags, read back from the device (valid until the next call).
  const uint8_t* downloadDirtyFlags();

  cudaStream_t stream_;
  size_t pool_max_bytes_;
  SlotPool pool_;
  BlockTransfer transfer_;
  HostOnlyIndex host_only_;      ///< host blocks without a slot
  bool host_only_stale_ = true;  ///< rebuild before it is next read
  bool any_dirty_ = false;
  uint32_t scan_ = 0;
  uint64_t uploaded_ = 0, evicted_ = 0;
  PinnedArray<uint32_t> last_used_host_;
  PinnedArray<uint8_t> dirty_host_;
  PinnedArray<BlockKey> keys_host_;
  PinnedArray<int32_t> touched_host_;
};

}  // namespace fragg::cuda
