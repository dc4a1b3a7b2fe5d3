#include "device_block_cache.h"

#include <algorithm>
#include <climits>
#include <cstdint>
#include <string>

#include "cuda_stream.h"

namespace fragg::cuda {

namespace {
bool inBox(const BlockKey& k, const BlockKey& lo, const BlockKey& hi) {
  return k.x >= lo.x && k.x <= hi.x && k.y >= lo.y && k.y <= hi.y && k.z >= lo.z && k.z <= hi.z;
}
}  // namespace

DeviceBlockCache::DeviceBlockCache(cudaStream_t stream, size_t pool_max_bytes, bool direct_uploads,
                                   int host_threads)
    : stream_(stream),
      pool_max_bytes_(pool_max_bytes),
      pool_(stream),
      transfer_(stream, direct_uploads, host_threads) {}

int32_t DeviceBlockCache::slotLimit() const {
  size_t bytes = pool_max_bytes_;
  if (bytes == 0) {
    size_t free_bytes = 0, total_bytes = 0;
    FRAGG_CUDA_CHECK(cudaMemGetInfo(&free_bytes, &total_bytes));
    bytes = pool_.deviceBytes() + free_bytes / 2;
  }
  return static_cast<int32_t>(
      std::min<size_t>(bytes / SlotPool::bytesPerSlot(), SlotPool::kMaxCapacity));
}

void DeviceBlockCache::reserve(int64_t slots) {
  if (pool_.capacity() > 0) return;
  pool_.grow(static_cast<int32_t>(std::min<int64_t>(slots, slotLimit())));
}

std::vector<BlockIndex> DeviceBlockCache::makeRoom(int32_t need, int32_t want, BlockMap& blocks) {
  want = std::max(want, need);
  std::vector<BlockIndex> evicted;
  if (freeSlots() >= want) return evicted;
  const int32_t cap = pool_.capacity();
  const int32_t limit = slotLimit();
  const int64_t grown =
      std::max<int64_t>(int64_t(cap) + cap / 2, int64_t(cap) + want - freeSlots());
  if (cap < limit) {
    try {
      pool_.grow(static_cast<int32_t>(std::min<int64_t>(grown, limit)));
    } catch (const CudaOutOfMemory&) {
      // Stay at this size; evict below.
    }
  }
  if (freeSlots() < want) evicted = evict(want - freeSlots(), blocks);
  if (freeSlots() < need)
    throw CudaOutOfMemory("device block pool of " + std::to_string(pool_.capacity()) +
                          " slots cannot hold the blocks of one scan");
  return evicted;
}

std::vector<BlockIndex> DeviceBlockCache::evict(int32_t n, BlockMap& blocks) {
  const int32_t cap = pool_.capacity();
  last_used_host_.reserve(size_t(cap));
  copyToHost(last_used_host_.get(), pool_.arrays().last_used, size_t(cap), stream_);
  FRAGG_CUDA_CHECK(cudaStreamSynchronize(stream_));
  const std::vector<int32_t> victims =
      leastRecentlyUsed(pool_.table(), last_used_host_.get(), scan_, size_t(n));
  std::vector<BlockIndex> out = dropSlots(victims, blocks);
  evicted_ += victims.size();
  return out;
}

std::vector<BlockIndex> DeviceBlockCache::dropSlots(const std::vector<int32_t>& slots,
                                                    BlockMap& blocks) {
  if (slots.empty()) return {};
  const uint8_t* dirty_flags = downloadDirtyFlags();
  std::vector<int32_t> dirty;
  for (int32_t s : slots)
    if (dirty_flags[s]) dirty.push_back(s);
  writeBack(dirty, blocks);
  std::vector<BlockIndex> released = pool_.release(slots);
  // A device-only slot that was never applied has no host block: nothing to keep.
  released.erase(std::remove(released.begin(), released.end(), kNoBlock), released.end());
  if (!host_only_stale_)
    for (BlockIndex i : released) host_only_.add(i, blocks.meta(i).key);
  return released;
}

void DeviceBlockCache::writeBack(const std::vector<int32_t>& slots, BlockMap& blocks) {
  transfer_.writeBack(pool_.arrays(), slots, blocks, [&](int32_t slot, const BlockKey& key) {
    BlockIndex i = pool_.table().blockOf(slot);
    if (i == kNoBlock) {  // created on the device: the host block is made now
      i = blocks.findOrCreate(key, nullptr, /*initialise=*/false);
      pool_.bind(slot, i);
    }
    return i;
  });
}

void DeviceBlockCache::upload(const std::vector<BlockIndex>& host_blocks, const BlockMap& blocks) {
  const std::vector<int32_t> slots = pool_.pop(static_cast<int32_t>(host_blocks.size()));
  transfer_.upload(pool_.arrays(), host_blocks, slots, blocks, scan_);
  for (size_t j = 0; j < host_blocks.size(); ++j) {
    pool_.bind(slots[j], host_blocks[j]);
    if (!host_only_stale_) host_only_.remove(host_blocks[j], blocks.meta(host_blocks[j]).key);
  }
  uploaded_ += host_blocks.size();
}

uint32_t DeviceBlockCache::adoptDeviceSlots(int32_t new_free_top) {
  return static_cast<uint32_t>(pool_.takenByDevice(new_free_top).size());
}

std::vector<BlockKey> DeviceBlockCache::keysMarked(uint32_t touched) {
  const int32_t cap = pool_.capacity();
  std::vector<BlockKey> keys;
  touched = std::min<uint32_t>(touched, static_cast<uint32_t>(cap));
  if (touched == 0) return keys;
  keys_host_.reserve(size_t(cap));
  touched_host_.reserve(touched);
  copyToHost(keys_host_.get(), pool_.arrays().keys, size_t(cap), stream_);
  copyToHost(touched_host_.get(), pool_.arrays().touched_list, size_t(touched), stream_);
  FRAGG_CUDA_CHECK(cudaStreamSynchronize(stream_));
  keys.reserve(touched);
  for (uint32_t j = 0; j < touched; ++j) keys.push_back(keys_host_[touched_host_[j]]);
  return keys;
}

void DeviceBlockCache::forEachHostOnlyIn(const BlockMap& blocks, const BlockKey& lo,
                                         const BlockKey& hi,
                                         const std::function<void(BlockIndex)>& fn) {
  if (host_only_stale_) {
    host_only_.clear();
    blocks.forEach([&](BlockIndex i) {
      if (slotOf(i) < 0) host_only_.add(i, blocks.meta(i).key);
    });
    host_only_stale_ = false;
  }
  host_only_.forEachInBox(blocks, lo, hi, fn);
}

void DeviceBlockCache::ensureResident(const std::vector<BlockKey>& keys, BlockMap& blocks) {
  std::vector<BlockIndex> wanted;
  for (const BlockKey& k : keys) {
    const BlockIndex i = blocks.find(k);
    if (i != kNoBlock && slotOf(i) < 0) wanted.push_back(i);
  }
  std::sort(wanted.begin(), wanted.end());
  wanted.erase(std::unique(wanted.begin(), wanted.end()), wanted.end());
  if (wanted.empty()) return;
  const int32_t n = static_cast<int32_t>(wanted.size());
  makeRoom(n, n, blocks);
  upload(wanted, blocks);
}

void DeviceBlockCache::ensureResident(const BlockKey& lo, const BlockKey& hi, BlockMap& blocks) {
  std::vector<BlockIndex> wanted;
  forEachHostOnlyIn(blocks, lo, hi, [&](BlockIndex i) { wanted.push_back(i); });
  if (wanted.empty()) return;
  const int32_t n = static_cast<int32_t>(wanted.size());
  makeRoom(n, n, blocks);
  upload(wanted, blocks);
}

const uint8_t* DeviceBlockCache::downloadDirtyFlags() {
  const size_t cap = size_t(pool_.capacity());
  dirty_host_.reserve(cap);
  copyToHost(dirty_host_.get(), pool_.arrays().dirty, cap, stream_);
  FRAGG_CUDA_CHECK(cudaStreamSynchronize(stream_));
  return dirty_host_.get();
}

void DeviceBlockCache::sync(BlockMap& blocks) { (void)syncSome(blocks, SIZE_MAX); }

bool DeviceBlockCache::syncSome(BlockMap& blocks, size_t max_blocks) {
  if (!any_dirty_) return false;
  max_blocks = std::max<size_t>(max_blocks, 1);
  const uint8_t* dirty_flags = downloadDirtyFlags();
  std::vector<int32_t> dirty;
  bool more = false;
  for (int32_t s = 0; s < pool_.capacity(); ++s) {
    if (!dirty_flags[s]) continue;
    if (dirty.size() == max_blocks) {
      more = true;
      break;
    }
    dirty.push_back(s);
  }
  writeBack(dirty, blocks);  // the download clears their dirty flags
  if (!more) any_dirty_ = false;
  return more;
}

void DeviceBlockCache::invalidate(const BlockKey& lo, const BlockKey& hi, BlockMap& blocks) {
  sync(blocks);  // device-only blocks get their host blocks (and keys) here
  std::vector<int32_t> inside;
  for (int32_t s = 0; s < pool_.capacity(); ++s) {
    const BlockIndex i = pool_.table().blockOf(s);
    if (pool_.table().resident(s) && i != kNoBlock && inBox(blocks.meta(i).key, lo, hi))
      inside.push_back(s);
  }
  pool_.release(inside);
  host_only_stale_ = true;  // the caller is about to change (or erase) those host blocks
}

void DeviceBlockCache::invalidateAll(BlockMap& blocks) {
  sync(blocks);
  pool_.clear();
  host_only_.clear();
  host_only_stale_ = true;  // the host map is about to change: rebuilt when next read
  any_dirty_ = false;
}

void DeviceBlockCache::forget(const std::vector<BlockIndex>& host_blocks, BlockMap& blocks) {
  std::vector<int32_t> slots;
  for (BlockIndex i : host_blocks) {
    const int32_t s = slotOf(i);
    if (s >= 0) slots.push_back(s);
  }
  dropSlots(slots, blocks);  // written back when dirty; their blocks are host-only now
  if (!host_only_stale_)
    for (BlockIndex i : host_blocks) host_only_.remove(i, blocks.meta(i).key);
}

void DeviceBlockCache::added(const std::vector<BlockIndex>& host_blocks, const BlockMap& blocks) {
  if (host_only_stale_) return;  // rebuilt from the host map when next read
  for (BlockIndex i : host_blocks) host_only_.add(i, blocks.meta(i).key);
}

}  // namespace fragg::cuda
