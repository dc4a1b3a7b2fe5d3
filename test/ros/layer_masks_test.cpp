// layerMasks (SSE2 where available) against the scalar reference, and against the cells'
// states as the occupancy model defines them.
#include "fragg_map/ros/layer_masks.h"

#include <gtest/gtest.h>

#include <cstdint>
#include <random>

#include "fragg_map/map.h"

namespace fragg::ros {
namespace {

TEST(LayerMasks, EqualTheScalarLoopAndTheModelsStates) {
  Map map;  // OctoMap's default model
  const OccupancyModel& model = map.model();
  const int16_t above = model.occupied_above_fx, below = model.free_below_fx;
  // Values around every threshold and at the ends of the range, then random ones.
  const int16_t edges[] = {kUnobservedLogOdds,
                           static_cast<int16_t>(kUnobservedLogOdds + 1),
                           static_cast<int16_t>(below - 1),
                           below,
                           static_cast<int16_t>(below + 1),
                           static_cast<int16_t>(above - 1),
                           above,
                           static_cast<int16_t>(above + 1),
                           0,
                           -1,
                           INT16_MAX,
                           model.min_fx,
                           model.max_fx};
  std::mt19937 rng(7);
  std::uniform_int_distribution<int> pick(0, static_cast<int>(std::size(edges)) - 1);
  std::uniform_int_distribution<int> any(INT16_MIN, INT16_MAX);
  size_t occupied = 0, free = 0, unknown = 0;
  for (int round = 0; round < 2000; ++round) {
    Cell cells[64];
    for (Cell& c : cells) {
      c.log_odds_fx = static_cast<int16_t>(round % 2 ? any(rng) : edges[pick(rng)]);
      c.hits = static_cast<int16_t>(any(rng));  // the other half of the word must not matter
    }
    const LayerMasks fast = layerMasks(cells, above, below);
    const LayerMasks ref = layerMasksScalar(cells, above, below);
    ASSERT_EQ(fast.occupied, ref.occupied) << "round " << round;
    ASSERT_EQ(fast.free, ref.free) << "round " << round;
    ASSERT_EQ(fast.observed, ref.observed) << "round " << round;
    for (int i = 0; i < 64; ++i) {
      const CellState s = model.state(cells[i]);
      ASSERT_EQ(fast.occupied >> i & 1, s == CellState::kOccupied) << cells[i].log_odds_fx;
      ASSERT_EQ(fast.free >> i & 1, s == CellState::kFree) << cells[i].log_odds_fx;
      ASSERT_EQ(fast.observed >> i & 1, cells[i].observed());
      occupied += s == CellState::kOccupied;
      free += s == CellState::kFree;
      unknown += s == CellState::kUnknown;
    }
  }
  EXPECT_GT(occupied, 0u);
  EXPECT_GT(free, 0u);
  EXPECT_GT(unknown, 0u);
}

}  // namespace
}  // namespace fragg::ros
