// OccupancyModel::unapply: undoing one update of a cell.
#include <gtest/gtest.h>

#include <random>
#include <vector>

#include "fragg_map/occupancy.h"

namespace fragg {
namespace {

OccupancyModel defaultModel() { return OccupancyModel::fromParams(OccupancyParams()); }

Cell replay(const OccupancyModel& m, const std::vector<bool>& updates) {
  Cell c;
  for (bool hit : updates) m.apply(c, hit);
  return c;
}

TEST(UnapplyTest, UndoingEveryUpdateLeavesTheCellUnobserved) {
  const OccupancyModel m = defaultModel();
  for (const std::vector<bool>& seq : {std::vector<bool>{true},
                                       {false},
                                       {true, false},
                                       {false, false, true},
                                       {true, true, false}}) {
    Cell c = replay(m, seq);
    ASSERT_TRUE(c.observed());
    for (bool hit : seq) m.unapply(c, hit);
    EXPECT_FALSE(c.observed()) << "log-odds " << c.log_odds_fx << " hits " << c.hits;
    EXPECT_EQ(c.hits, 0);
  }
}

TEST(UnapplyTest, WithoutClampingRemovalEqualsTheHistoryWithoutThatUpdate) {
  // Random short histories that never reach a clamping bound (default model: 4 hits reach
  // 3,468 < 3,476; 4 misses reach -1,660 > -2,036): removing any one update gives exactly the
  // cell built from the other updates, hit count included.
  const OccupancyModel m = defaultModel();
  std::mt19937 rng(7);
  int checked = 0;
  for (int trial = 0; trial < 2000; ++trial) {
    std::vector<bool> seq(1 + rng() % 4);
    for (size_t i = 0; i < seq.size(); ++i) seq[i] = rng() % 2;
    const size_t drop = rng() % seq.size();
    Cell c = replay(m, seq);
    m.unapply(c, seq[drop]);
    std::vector<bool> rest = seq;
    rest.erase(rest.begin() + static_cast<long>(drop));
    const Cell want = replay(m, rest);
    ASSERT_EQ(c.observed(), want.observed());
    ASSERT_EQ(c.log_odds_fx, want.log_odds_fx);
    ASSERT_EQ(c.hits, want.hits);
    ++checked;
  }
  EXPECT_EQ(checked, 2000);
}

TEST(UnapplyTest, ClampedCellsStayWithinTheBoundsOfTheirEvidence) {
  const OccupancyModel m = defaultModel();
  // Ten misses saturate at min; taking five back must not make the cell occupied.
  Cell free_cell = replay(m, std::vector<bool>(10, false));
  EXPECT_EQ(free_cell.log_odds_fx, m.min_fx);
  for (int i = 0; i < 5; ++i) m.unapply(free_cell, false);
  EXPECT_NE(m.state(free_cell), CellState::kOccupied);
  // A cell with one hit left cannot hold more than one hit's log-odds.
  Cell wall = replay(m, std::vector<bool>(10, true));
  EXPECT_EQ(wall.log_odds_fx, m.max_fx);
  for (int i = 0; i < 9; ++i) m.unapply(wall, true);
  EXPECT_EQ(wall.hits, 1);
  EXPECT_LE(wall.log_odds_fx, m.hit_fx);
  m.unapply(wall, true);
  EXPECT_FALSE(wall.observed());
}

TEST(UnapplyTest, UnobservedCellsStayUnobserved) {
  const OccupancyModel m = defaultModel();
  Cell c;
  m.unapply(c, true);
  EXPECT_FALSE(c.observed());
  m.unapply(c, false);
  EXPECT_FALSE(c.observed());
  EXPECT_EQ(c.hits, 0);
}

}  // namespace
}  // namespace fragg
