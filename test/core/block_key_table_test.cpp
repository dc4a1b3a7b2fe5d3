// BlockKeyTable (the block index of BlockMap and the planning tier): random inserts and
// erasures against std::map, keys that crowd into one probe run (erasure's backward shift
// across the end of the array), growth, clear and moves.
#include "fragg_map/block_key_table.h"

#include <gtest/gtest.h>

#include <algorithm>
#include <map>
#include <random>
#include <tuple>
#include <vector>

namespace fragg {
namespace {

struct KeyLess {
  bool operator()(const BlockKey& a, const BlockKey& b) const {
    return std::tie(a.x, a.y, a.z) < std::tie(b.x, b.y, b.z);
  }
};
using Reference = std::map<BlockKey, uint32_t, KeyLess>;

void expectSame(const BlockKeyTable& table, const Reference& ref) {
  ASSERT_EQ(table.size(), ref.size());
  for (const auto& [k, v] : ref) ASSERT_EQ(table.find(k), v) << k.x << " " << k.y << " " << k.z;
  Reference seen;
  table.forEach([&](const BlockKey& k, uint32_t v) { EXPECT_TRUE(seen.emplace(k, v).second); });
  EXPECT_EQ(seen, ref);
}

TEST(BlockKeyTable, RandomInsertsAndErasuresMatchAReference) {
  std::mt19937 rng(7);
  // A small key range: erasures often hit, and lookups of absent keys are common too.
  std::uniform_int_distribution<int32_t> coord(-12, 12);
  BlockKeyTable table;
  Reference ref;
  for (int step = 0; step < 200000; ++step) {
    const BlockKey k{coord(rng), coord(rng), coord(rng)};
    const bool there = ref.count(k) != 0;
    if (rng() % 3 == 0) {
      EXPECT_EQ(table.erase(k), there);
      ref.erase(k);
    } else if (!there) {
      table.insert(k, static_cast<uint32_t>(step));
      ref[k] = static_cast<uint32_t>(step);
    } else {
      EXPECT_EQ(table.find(k), ref[k]);
    }
    if (step % 20000 == 0) expectSame(table, ref);
  }
  expectSame(table, ref);
  // Absent keys are not found.
  EXPECT_EQ(table.find({1000, 0, 0}), BlockKeyTable::kNone);
  EXPECT_FALSE(table.erase({1000, 0, 0}));
}

TEST(BlockKeyTable, ErasureKeepsEveryKeyOfACrowdedRunReachable) {
  // 64 slots (the smallest table) hold up to 32 keys: fill it to the brim with keys, then
  // erase them one by one in every order a seed gives, checking all the others each time.
  // Probe runs wrap around the end of the array and cross each other's homes.
  for (unsigned seed = 0; seed < 50; ++seed) {
    std::mt19937 rng(seed);
    BlockKeyTable table;
    table.reserve(32);
    Reference ref;
    while (ref.size() < 32) {
      const BlockKey k{static_cast<int32_t>(rng() % 1000), static_cast<int32_t>(rng() % 7), 0};
      if (ref.emplace(k, static_cast<uint32_t>(ref.size())).second) table.insert(k, ref[k]);
    }
    expectSame(table, ref);
    std::vector<BlockKey> order;
    for (const auto& kv : ref) order.push_back(kv.first);
    std::shuffle(order.begin(), order.end(), rng);
    for (const BlockKey& k : order) {
      ASSERT_TRUE(table.erase(k));
      ref.erase(k);
      expectSame(table, ref);
    }
    EXPECT_TRUE(table.empty());
  }
}

TEST(BlockKeyTable, GrowsClearsAndMoves) {
  BlockKeyTable table;
  EXPECT_EQ(table.find({0, 0, 0}), BlockKeyTable::kNone);  // empty: no slots at all
  Reference ref;
  for (int32_t i = 0; i < 100000; ++i) {
    const BlockKey k{i % 97, i / 97, -i};
    table.insert(k, static_cast<uint32_t>(i));
    ref[k] = static_cast<uint32_t>(i);
  }
  expectSame(table, ref);
  EXPECT_GE(table.bytes(), 2 * ref.size() * 16);  // at most half full
  BlockKeyTable moved(std::move(table));
  expectSame(moved, ref);
  EXPECT_EQ(table.size(), 0u);
  EXPECT_EQ(table.find({0, 0, 0}), BlockKeyTable::kNone);
  table.insert({5, 5, 5}, 1);  // a moved-from table is usable
  EXPECT_EQ(table.find({5, 5, 5}), 1u);
  moved.clear();
  EXPECT_EQ(moved.size(), 0u);
  EXPECT_EQ(moved.bytes(), 0u);
  EXPECT_EQ(moved.find({0, 0, 0}), BlockKeyTable::kNone);
}

}  // namespace
}  // namespace fragg
