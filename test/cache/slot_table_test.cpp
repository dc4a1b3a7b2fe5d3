// SlotTable: the host's book of the device slot pool (free stack, residency, block <-> slot).
#include "slot_table.h"

#include <gtest/gtest.h>

#include <algorithm>
#include <set>
#include <vector>

#include "fragg_map/errors.h"

namespace fragg::cuda {
namespace {

TEST(SlotTable, GrowPutsNewSlotsOnTheFreeStackLowestOnTop) {
  SlotTable t;
  t.grow(4);
  EXPECT_EQ(t.capacity(), 4);
  EXPECT_EQ(t.freeCount(), 4);
  // Popping takes from the top: slot 0 first, as the device's stack does.
  EXPECT_EQ(t.pop(1), std::vector<int32_t>{0});
  t.grow(6);
  EXPECT_EQ(t.capacity(), 6);
  EXPECT_EQ(t.freeCount(), 5);
  const std::vector<int32_t> next = t.pop(2);
  EXPECT_EQ(next, (std::vector<int32_t>{5, 4}));  // the new slots sit above the old ones
  t.grow(3);                                      // never shrinks
  EXPECT_EQ(t.capacity(), 6);
}

TEST(SlotTable, PopThrowsWhenShortAndLeavesTheStack) {
  SlotTable t;
  t.grow(3);
  EXPECT_THROW(t.pop(4), CudaError);
  EXPECT_EQ(t.freeCount(), 3);
  EXPECT_THROW(t.pop(-1), CudaError);
  EXPECT_EQ(t.pop(3).size(), 3u);
  EXPECT_THROW(t.pop(1), CudaError);
  EXPECT_TRUE(t.pop(0).empty());
}

TEST(SlotTable, BindAndUnbindKeepBothDirections) {
  SlotTable t;
  t.grow(8);
  const std::vector<int32_t> s = t.pop(3);
  t.bind(s[0], 10);
  t.bind(s[1], 3);
  t.bind(s[2], kNoBlock);  // device-only block
  EXPECT_TRUE(t.resident(s[0]) && t.resident(s[1]) && t.resident(s[2]));
  EXPECT_EQ(t.slotOf(10), s[0]);
  EXPECT_EQ(t.slotOf(3), s[1]);
  EXPECT_EQ(t.slotOf(4), -1);
  EXPECT_EQ(t.slotOf(1000000), -1);  // beyond every index seen
  EXPECT_EQ(t.blockOf(s[2]), kNoBlock);
  EXPECT_EQ(t.unbind(s[0]), 10u);
  EXPECT_FALSE(t.resident(s[0]));
  EXPECT_EQ(t.slotOf(10), -1);
  EXPECT_EQ(t.blockOf(s[0]), kNoBlock);
  EXPECT_EQ(t.unbind(s[2]), kNoBlock);
  t.push({s[0], s[2]});
  EXPECT_EQ(t.freeCount(), 7);
}

TEST(SlotTable, DeviceAllocationsAreResidentAndDeviceOnly) {
  SlotTable t;
  t.grow(10);
  // The ray kernel popped 3 slots: the device's top went from 10 to 7.
  const std::vector<int32_t> taken = t.takenByDevice(7);
  ASSERT_EQ(taken.size(), 3u);
  EXPECT_EQ(t.freeCount(), 7);
  for (int32_t s : taken) {
    EXPECT_TRUE(t.resident(s));
    EXPECT_EQ(t.blockOf(s), kNoBlock);
  }
  // The same slots are what pop(3) would have handed out.
  EXPECT_EQ(std::set<int32_t>(taken.begin(), taken.end()), (std::set<int32_t>{0, 1, 2}));
  EXPECT_TRUE(t.takenByDevice(7).empty());    // no change
  EXPECT_TRUE(t.takenByDevice(9).empty());    // above the top: nothing taken
  EXPECT_EQ(t.takenByDevice(-4).size(), 7u);  // an overflowed pass drives the top negative
  EXPECT_EQ(t.freeCount(), 0);
}

TEST(SlotTable, CountsTheDeviceOnlySlotsUntilTheyGetHostBlocksOrGo) {
  SlotTable t;
  t.grow(12);
  for (int32_t s : t.pop(2)) t.bind(s, BlockIndex(s + 50));  // host uploads: not counted
  EXPECT_EQ(t.deviceOnlyCount(), 0);
  const std::vector<int32_t> taken = t.takenByDevice(6);  // the rays took 4 slots
  ASSERT_EQ(taken.size(), 4u);
  EXPECT_EQ(t.deviceOnlyCount(), 4);
  t.bind(taken[0], BlockIndex(7));  // written back: a host block now
  EXPECT_EQ(t.deviceOnlyCount(), 3);
  t.bind(taken[0], BlockIndex(8));  // bound again to another host block: no change
  EXPECT_EQ(t.deviceOnlyCount(), 3);
  EXPECT_EQ(t.unbind(taken[1]), kNoBlock);  // released without a host block
  t.push({taken[1]});
  EXPECT_EQ(t.deviceOnlyCount(), 2);
  t.unbind(taken[1]);  // unbinding a free slot again changes nothing
  EXPECT_EQ(t.deviceOnlyCount(), 2);
  t.unbind(taken[0]);  // a slot with a host block: not counted before either
  EXPECT_EQ(t.deviceOnlyCount(), 2);
  // Brute force over the table agrees.
  int32_t device_only = 0;
  for (int32_t s = 0; s < t.capacity(); ++s)
    device_only += t.resident(s) && t.blockOf(s) == kNoBlock ? 1 : 0;
  EXPECT_EQ(device_only, 2);
  t.clear();
  EXPECT_EQ(t.deviceOnlyCount(), 0);
}

TEST(SlotTable, PushRefusesMoreSlotsThanTheStackHolds) {
  SlotTable t;
  t.grow(2);
  EXPECT_THROW(t.push({0}), CudaError);  // both slots are already free
  EXPECT_EQ(t.freeCount(), 2);
}

TEST(SlotTable, ClearFreesEverySlotAndForgetsBlocks) {
  SlotTable t;
  t.grow(5);
  for (int32_t s : t.pop(4)) t.bind(s, BlockIndex(s + 100));
  t.clear();
  EXPECT_EQ(t.freeCount(), 5);
  for (int32_t s = 0; s < 5; ++s) {
    EXPECT_FALSE(t.resident(s));
    EXPECT_EQ(t.blockOf(s), kNoBlock);
    EXPECT_EQ(t.slotOf(BlockIndex(s + 100)), -1);
  }
  EXPECT_EQ(t.pop(1), std::vector<int32_t>{0});
}

TEST(SlotTable, LeastRecentlyUsedSkipsFreeSlotsAndTheCurrentScan) {
  SlotTable t;
  t.grow(6);
  for (int32_t s : t.pop(6)) t.bind(s, BlockIndex(s));
  ASSERT_EQ(t.unbind(4), 4u);  // slot 4 free again
  t.push({4});
  const uint32_t last_used[6] = {7, 3, 9, 5, 1, 9};
  // Scan 9 is running: slots 2 and 5 are in use; slot 4 is free.
  EXPECT_EQ(leastRecentlyUsed(t, last_used, 9, 2), (std::vector<int32_t>{1, 3}));
  const std::vector<int32_t> all = leastRecentlyUsed(t, last_used, 9, 100);
  EXPECT_EQ(all, (std::vector<int32_t>{1, 3, 0}));
  EXPECT_TRUE(leastRecentlyUsed(t, last_used, 9, 0).empty());
}

}  // namespace
}  // namespace fragg::cuda
