// Byte comparison of two maps built by the same operations: the same blocks with the same
// 2 KiB of cells, and as many changed blocks.
#pragma once

#include <gtest/gtest.h>

#include <cstring>

#include "fragg_map/map.h"

namespace fragg::test {

inline void expectSameMap(const Map& a, const Map& b, const char* what) {
  ASSERT_EQ(a.blockCount(), b.blockCount()) << what;
  size_t differing = 0, missing = 0;
  a.forEachBlock([&](const BlockKey& k, const Block& block) {
    const Block* other = b.findBlock(k);
    if (!other) {
      ++missing;
      return;
    }
    if (std::memcmp(&block, other, sizeof(Block)) != 0) ++differing;
  });
  EXPECT_EQ(missing, 0u) << what;
  EXPECT_EQ(differing, 0u) << what;
  EXPECT_EQ(a.changedBlocksSince(0).size(), b.changedBlocksSince(0).size()) << what;
}

}  // namespace fragg::test
