// HostOnlyIndex: host blocks without a device slot, found by box in time that follows them.
#include "host_only_index.h"

#include <gtest/gtest.h>

#include <algorithm>
#include <random>
#include <vector>

namespace fragg::cuda {
namespace {

bool inBox(const BlockKey& k, const BlockKey& lo, const BlockKey& hi) {
  return k.x >= lo.x && k.x <= hi.x && k.y >= lo.y && k.y <= hi.y && k.z >= lo.z && k.z <= hi.z;
}

std::vector<BlockIndex> listed(const HostOnlyIndex& index, const BlockMap& blocks,
                               const BlockKey& lo, const BlockKey& hi) {
  std::vector<BlockIndex> out;
  index.forEachInBox(blocks, lo, hi, [&](BlockIndex i) { out.push_back(i); });
  std::sort(out.begin(), out.end());
  return out;
}

TEST(HostOnlyIndex, BoxQueriesMatchABruteForceFilter) {
  std::mt19937 rng(7);
  std::uniform_int_distribution<int32_t> coord(-40, 40);
  BlockMap blocks;
  HostOnlyIndex index;
  std::vector<BlockIndex> members;
  for (int n = 0; n < 600; ++n) {
    bool created = false;
    const BlockIndex i = blocks.findOrCreate({coord(rng), coord(rng), coord(rng)}, &created);
    if (!created) continue;
    // Every third block has a slot (not listed).
    if (n % 3 != 0) {
      index.add(i, blocks.meta(i).key);
      members.push_back(i);
    }
  }
  for (int q = 0; q < 200; ++q) {
    BlockKey lo{coord(rng), coord(rng), coord(rng)}, hi{coord(rng), coord(rng), coord(rng)};
    if (lo.x > hi.x) std::swap(lo.x, hi.x);
    if (lo.y > hi.y) std::swap(lo.y, hi.y);
    if (lo.z > hi.z) std::swap(lo.z, hi.z);
    if (q % 10 == 0) lo = {-1000, -1000, -1000};  // boxes larger than the index: the other path
    std::vector<BlockIndex> expected;
    for (BlockIndex i : members)
      if (inBox(blocks.meta(i).key, lo, hi)) expected.push_back(i);
    std::sort(expected.begin(), expected.end());
    ASSERT_EQ(listed(index, blocks, lo, hi), expected) << "query " << q;
  }
}

TEST(HostOnlyIndex, RemoveTakesOneBlockAndRebuildListsAll) {
  BlockMap blocks;
  const BlockIndex a = blocks.findOrCreate({0, 0, 0});
  const BlockIndex b = blocks.findOrCreate({1, 0, 0});   // same coarse cell as a
  const BlockIndex c = blocks.findOrCreate({-9, 0, 0});  // another coarse cell
  HostOnlyIndex index;
  for (BlockIndex i : {a, b, c}) index.add(i, blocks.meta(i).key);
  const BlockKey lo{-100, -100, -100}, hi{100, 100, 100};
  index.remove(b, blocks.meta(b).key);
  EXPECT_EQ(listed(index, blocks, lo, hi), (std::vector<BlockIndex>{a, c}));
  index.remove(b, blocks.meta(b).key);  // not listed: no effect
  index.remove(c, blocks.meta(c).key);
  EXPECT_EQ(listed(index, blocks, lo, hi), (std::vector<BlockIndex>{a}));
  index.rebuild(blocks);
  EXPECT_EQ(listed(index, blocks, lo, hi), (std::vector<BlockIndex>{a, b, c}));
  index.clear();
  EXPECT_TRUE(listed(index, blocks, lo, hi).empty());
}

}  // namespace
}  // namespace fragg::cuda
