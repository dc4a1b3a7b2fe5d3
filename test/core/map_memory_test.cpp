// Map::memory()'s known_voxels (a walk over every live block, on several threads): the observed
// cells of the blocks in the map, counted against a lookup of every cell that was written,
// after an erase freed slots in the middle of the arena.
#include <gtest/gtest.h>

#include <vector>

#include "fragg_map/map.h"

namespace fragg {
namespace {

TEST(MapMemory, KnownVoxelsAreTheObservedCellsOfTheLiveBlocks) {
  MapParams params;
  params.resolution_m = 0.1;
  params.backend = Backend::kCpu;
  params.threads = 2;
  Map map(params);
  // 20 x 20 x 12 blocks (more than the walk's threshold for threads), a few cells each: some
  // observed (occupied, free, in the unknown band), some written back to unobserved.
  std::vector<VoxelKey> written;
  map.writeCells([&](CellWriter& w) {
    for (int32_t bz = 0; bz < 12; ++bz)
      for (int32_t by = 0; by < 20; ++by)
        for (int32_t bx = 0; bx < 20; ++bx)
          for (int32_t i = 0; i < 8; ++i) {
            const VoxelKey k{bx * 8 + i, by * 8 + (i * 3) % 8, bz * 8 + (i * 5) % 8};
            Cell c;
            const int pick = (bx + by + bz + i) % 5;
            c.log_odds_fx = pick == 0   ? kUnobservedLogOdds
                            : pick == 1 ? map.model().max_fx
                            : pick == 2 ? map.model().min_fx
                            : pick == 3 ? int16_t{40}
                                        : int16_t{-700};
            w.set(k, c);
            written.push_back(k);
          }
  });
  const auto lookedUp = [&] {
    size_t n = 0;
    for (const VoxelKey& k : written) {
      const Cell* c = map.findCell(k);
      n += c && c->observed() ? 1 : 0;
    }
    return n;
  };
  const size_t before = lookedUp();
  ASSERT_GT(before, 4800u * 5);
  EXPECT_EQ(map.memory().known_voxels, before);
  // Erase a slab through the middle: its blocks' slots are freed between live ones.
  map.clearBox(Eigen::Vector3d(-1.0, 4.0, -1.0), Eigen::Vector3d(20.0, 8.0, 20.0));
  const size_t after = lookedUp();
  ASSERT_LT(after, before);
  ASSERT_GT(after, 0u);
  EXPECT_EQ(map.memory().known_voxels, after);
  EXPECT_LT(map.memory().blocks, 4800u);
}

}  // namespace
}  // namespace fragg
