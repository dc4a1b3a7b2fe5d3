// Dynamic mapping (MapParams::dynamic, both void rules) with out-of-core paging on the CPU
// backend: a map built with a small RAM budget, whose blocks page out and back in while a
// person walks through the corridor, equals the map built in memory cell for cell, and every
// scan classifies the same hits as dynamic. The void rules read cells beyond the ones a ray
// marks (the hit's neighbours, the 27 blocks around a passed-through block): a block paged out
// there must not read as never observed.
#include <gtest/gtest.h>

#include <string>
#include <vector>

#include "../test_dir.h"
#include "dynamic_corridor.h"
#include "fragg_map/store/page_stores.h"

namespace fragg::test {
namespace {

constexpr int kScans = 40;

void expectPagedEqualsMemory(VoidSpaceRule rule) {
  const std::string dir = testDir();
  Map paged(dynamicCorridorParams(rule)), memory(dynamicCorridorParams(rule));
  paged.attachPageStore(openPageStore(dir + "/map.db", false), corridorBudget(10.0, 5));
  uint64_t dynamic_hits = 0;
  for (int i = 0; i < kScans; ++i) {
    const Eigen::Isometry3d T = corridorPose(i, kScans);
    const PointCloud cloud = walkerCorridorScan(i, kScans, T);
    const InsertStats in_memory = memory.insert(cloud, T, corridorSensor());
    const InsertStats with_paging = paged.insert(cloud, T, corridorSensor());
    ASSERT_EQ(with_paging.rays_dynamic, in_memory.rays_dynamic) << "scan " << i;
    ASSERT_EQ(with_paging.rays_hit, in_memory.rays_hit) << "scan " << i;
    dynamic_hits += in_memory.rays_dynamic;
  }
  const PagingStats st = paged.pagingStats();
  EXPECT_GT(st.pages_evicted, 500u) << "nothing paged out: the test pages nothing";
  EXPECT_GT(st.pages_read, 50u) << "the way back paged nothing in";
  EXPECT_GT(dynamic_hits, 100u)
      << "the walker's hits were never dynamic: the rule was not exercised";
  paged.ensureAllResident();
  std::string why;
  EXPECT_TRUE(sameBlocks(paged, memory, &why)) << why;
}

TEST(DynamicPaging, PassThroughRulePagedEqualsInMemory) {
  expectPagedEqualsMemory(VoidSpaceRule::kPassThrough);
}

TEST(DynamicPaging, SurroundRulePagedEqualsInMemory) {
  expectPagedEqualsMemory(VoidSpaceRule::kSurround);
}

}  // namespace
}  // namespace fragg::test
