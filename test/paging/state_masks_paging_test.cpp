// The state-mask layer (issue 34 item 1) under out-of-core paging on the CPU backend: blocks
// paged back in (by the rays, by edits, by queries) come with masks equal to the reference,
// and a map read from its store has the in-memory map's masks.
#include <gtest/gtest.h>

#include <string>

#include "../core/state_masks_check.h"
#include "../test_dir.h"
#include "fragg_map/store/page_stores.h"
#include "paging_scenes.h"

namespace fragg::test {
namespace {

constexpr int kScans = 60;

PagingPolicy tinyBudget() { return corridorBudget(10.0, 5); }

TEST(StateMasksPaging, PagedInBlocksComeWithCurrentMasks) {
  const std::string dir = testDir();
  Map paged(corridorParams()), memory(corridorParams());
  paged.attachPageStore(openPageStore(dir + "/map.db", false), tinyBudget());
  std::string first;
  for (int i = 0; i < kScans; ++i) {
    const Eigen::Isometry3d T = corridorPose(i, kScans);
    paged.insert(corridorScan(T), T, corridorSensor());
    memory.insert(corridorScan(T), T, corridorSensor());
    ASSERT_EQ(blocksWithStaleMasks(paged, &first), 0u) << "after scan " << i << ": " << first;
  }
  const PagingStats st = paged.pagingStats();
  EXPECT_GT(st.pages_evicted, 500u);
  EXPECT_GT(st.pages_read, 50u) << "the way back paged nothing in";

  // An edit pages its box in first; a query pages its block in.
  paged.clearBox(Eigen::Vector3d(10.02, -1.0, 0.4), Eigen::Vector3d(12.5, 4.5, 2.2));
  memory.clearBox(Eigen::Vector3d(10.02, -1.0, 0.4), Eigen::Vector3d(12.5, 4.5, 2.2));
  EXPECT_EQ(blocksWithStaleMasks(paged, &first), 0u) << "clearBox: " << first;
  (void)paged.query(Eigen::Vector3d(30.05, 3.9, 1.0));
  EXPECT_EQ(blocksWithStaleMasks(paged, &first), 0u) << "query: " << first;

  // Every block back in RAM: the in-memory map's masks, byte for byte.
  paged.ensureAllResident();
  EXPECT_EQ(blocksWithStaleMasks(paged, &first), 0u) << "ensureAllResident: " << first;
  EXPECT_EQ(blocksWithOtherMasks(paged, memory, &first), 0u) << first;
  EXPECT_EQ(blocksWithOtherMasks(memory, paged, &first), 0u) << first;

  // The store read whole into another map.
  paged.commitPages();
  auto store = openPageStore(dir + "/map.db", true);
  const Map read = Map::loadPageStore(*store, corridorParams());
  EXPECT_EQ(blocksWithStaleMasks(read, &first), 0u) << "loadPageStore: " << first;
  EXPECT_EQ(blocksWithOtherMasks(read, memory, &first), 0u) << first;
}

}  // namespace
}  // namespace fragg::test
