// The CUDA backend's device block cache on its own: uploads and write-backs are byte-exact,
// ensureResident / invalidate / sync keep the host's book right, evictions pick the least
// recently used slots and write dirty ones back. Needs a device (skips without one).
#include "device_block_cache.h"

#include <gtest/gtest.h>

#include <cstring>
#include <random>
#include <string>
#include <vector>

#include "cuda_stream.h"
#include "fragg_map/internal/backend_factory.h"
#include "gpu_test_util.h"
#include "kernels.h"
#include "pinned_allocator.h"

namespace fragg::cuda {
namespace {

/// Host blocks on a 6 x 6 x 2 grid of keys with random cells.
std::vector<BlockIndex> fillBlocks(BlockMap& blocks, uint32_t seed) {
  std::mt19937 rng(seed);
  std::uniform_int_distribution<int> value(-2000, 2000);
  std::vector<BlockIndex> out;
  for (int32_t z = 0; z < 2; ++z)
    for (int32_t y = 0; y < 6; ++y)
      for (int32_t x = 0; x < 6; ++x) {
        const BlockIndex i = blocks.findOrCreate({x - 3, y - 3, z});
        for (Cell& c : blocks.block(i).cells) {
          c.log_odds_fx = static_cast<int16_t>(value(rng));
          c.hits = static_cast<int16_t>(value(rng) & 7);
        }
        out.push_back(i);
      }
  return out;
}

std::vector<uint8_t> bytesOf(const BlockMap& blocks, BlockIndex i) {
  const auto* p = reinterpret_cast<const uint8_t*>(&blocks.block(i));
  return std::vector<uint8_t>(p, p + sizeof(Block));
}

/// Marks the slots of these host blocks dirty (those that have one), as an apply pass would.
void markDirty(DeviceBlockCache& cache, const std::vector<BlockIndex>& host_blocks,
               cudaStream_t stream) {
  const SlotArrays a = cache.arrays();
  for (BlockIndex i : host_blocks)
    if (cache.slotOf(i) >= 0)
      FRAGG_CUDA_CHECK(cudaMemsetAsync(a.dirty + cache.slotOf(i), 1, 1, stream));
  FRAGG_CUDA_CHECK(cudaStreamSynchronize(stream));
  cache.markDirty();
}

class DeviceBlockCacheTest : public ::testing::TestWithParam<bool> {};

TEST_P(DeviceBlockCacheTest, UploadsAndWriteBacksAreByteExact) {
  REQUIRE_DEVICE();
  const bool direct = GetParam();  // pinned host blocks read in place, or staged copies
  CudaStream stream;
  BlockMap blocks(direct ? pinnedChunkAllocator() : plainChunkAllocator());
  const std::vector<BlockIndex> all = fillBlocks(blocks, 1);
  std::vector<std::vector<uint8_t>> before;
  for (BlockIndex i : all) before.push_back(bytesOf(blocks, i));
  DeviceBlockCache cache(stream.get(), 0, direct, 4);
  cache.reserve(256);
  cache.beginScan();
  // By keys: existing ones uploaded once, missing ones skipped.
  cache.ensureResident({blocks.meta(all[0]).key, blocks.meta(all[0]).key, BlockKey{90, 90, 90}},
                       blocks);
  EXPECT_GE(cache.slotOf(all[0]), 0);
  EXPECT_EQ(cache.uploadedCount(), 1u);
  // By box: every host-only block inside.
  cache.ensureResident(BlockKey{-3, -3, 0}, BlockKey{2, 2, 0}, blocks);
  EXPECT_EQ(cache.uploadedCount(), 36u);
  for (BlockIndex i : all) EXPECT_EQ(cache.slotOf(i) >= 0, blocks.meta(i).key.z == 0);
  EXPECT_FALSE(cache.needsSync());
  // Spoil the host copies, then write the device copies back: the bytes come home.
  for (BlockIndex i : all)
    if (cache.slotOf(i) >= 0)
      std::memset(static_cast<void*>(&blocks.block(i)), 0x5a, sizeof(Block));
  markDirty(cache, all, stream.get());
  cache.sync(blocks);
  EXPECT_FALSE(cache.needsSync());
  for (size_t j = 0; j < all.size(); ++j) ASSERT_EQ(bytesOf(blocks, all[j]), before[j]) << j;
}

INSTANTIATE_TEST_SUITE_P(Uploads, DeviceBlockCacheTest, ::testing::Values(true, false));

TEST(DeviceBlockCache, InvalidateDropsOnlyTheBoxAndWritesBackFirst) {
  REQUIRE_DEVICE();
  CudaStream stream;
  BlockMap blocks;
  const std::vector<BlockIndex> all = fillBlocks(blocks, 2);
  DeviceBlockCache cache(stream.get(), 0, false, 4);
  cache.reserve(256);
  cache.beginScan();
  cache.ensureResident(BlockKey{-10, -10, -10}, BlockKey{10, 10, 10}, blocks);
  std::vector<std::vector<uint8_t>> before;
  for (BlockIndex i : all) before.push_back(bytesOf(blocks, i));
  for (BlockIndex i : all) std::memset(static_cast<void*>(&blocks.block(i)), 0, sizeof(Block));
  markDirty(cache, all, stream.get());
  const int32_t free_before = cache.freeSlots();
  cache.invalidate(BlockKey{0, 0, 0}, BlockKey{2, 2, 1}, blocks);  // 3 x 3 x 2 = 18 blocks
  EXPECT_EQ(cache.freeSlots(), free_before + 18);
  for (size_t j = 0; j < all.size(); ++j) {
    const BlockKey k = blocks.meta(all[j]).key;
    const bool inside = k.x >= 0 && k.y >= 0;
    EXPECT_EQ(cache.slotOf(all[j]) < 0, inside) << j;
    EXPECT_EQ(bytesOf(blocks, all[j]), before[j]) << "written back before the drop: " << j;
  }
  // The dropped blocks are host-only again: a box request uploads exactly them.
  const uint64_t uploaded = cache.uploadedCount();
  cache.ensureResident(BlockKey{-10, -10, -10}, BlockKey{10, 10, 10}, blocks);
  EXPECT_EQ(cache.uploadedCount(), uploaded + 18);
  cache.invalidateAll(blocks);
  for (BlockIndex i : all) EXPECT_LT(cache.slotOf(i), 0);
}

TEST(DeviceBlockCache, EvictionTakesTheLeastRecentlyUsedAndKeepsTheCurrentScan) {
  REQUIRE_DEVICE();
  CudaStream stream;
  BlockMap blocks;
  const std::vector<BlockIndex> all = fillBlocks(blocks, 3);  // 72 blocks
  // A pool of exactly 40 slots.
  DeviceBlockCache cache(stream.get(), 40 * SlotPool::bytesPerSlot(), false, 4);
  cache.reserve(1000);
  ASSERT_EQ(cache.freeSlots(), 40);
  cache.beginScan();  // scan 1: the first 20 blocks
  std::vector<BlockKey> first, second, third;
  for (size_t j = 0; j < 20; ++j) first.push_back(blocks.meta(all[j]).key);
  for (size_t j = 20; j < 40; ++j) second.push_back(blocks.meta(all[j]).key);
  for (size_t j = 40; j < 60; ++j) third.push_back(blocks.meta(all[j]).key);
  cache.ensureResident(first, blocks);
  cache.beginScan();  // scan 2: 20 more, the pool is full
  cache.ensureResident(second, blocks);
  EXPECT_EQ(cache.freeSlots(), 0);
  std::vector<std::vector<uint8_t>> before;
  for (BlockIndex i : all) before.push_back(bytesOf(blocks, i));
  markDirty(cache, all, stream.get());
  for (size_t j = 0; j < 20; ++j)
    std::memset(static_cast<void*>(&blocks.block(all[j])), 0, sizeof(Block));
  cache.beginScan();  // scan 3: 20 new blocks push out scan 1's, written back first
  cache.ensureResident(third, blocks);
  EXPECT_EQ(cache.evictedCount(), 20u);
  for (size_t j = 0; j < 60; ++j) EXPECT_EQ(cache.slotOf(all[j]) >= 0, j >= 20) << j;
  for (size_t j = 0; j < 20; ++j) EXPECT_EQ(bytesOf(blocks, all[j]), before[j]) << j;
  // The current scan's own slots are never evicted: asking for more than the rest fails.
  EXPECT_THROW(cache.makeRoom(21, 21, blocks), CudaOutOfMemory);
}

}  // namespace
}  // namespace fragg::cuda
