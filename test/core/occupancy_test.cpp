#include "fragg_map/occupancy.h"

#include <gtest/gtest.h>

#include <cmath>

#include "fragg_map/errors.h"

namespace fragg {
namespace {

TEST(OccupancyTest, FixedPointMatchesFloatLogOdds) {
  const OccupancyModel m = OccupancyModel::fromParams(OccupancyParams());
  EXPECT_NEAR(m.hit_fx / 1024.0, logOdds(0.7), 0.5 / 1024);
  EXPECT_NEAR(m.miss_fx / 1024.0, logOdds(0.4), 0.5 / 1024);
  EXPECT_NEAR(m.min_fx / 1024.0, logOdds(0.12), 0.5 / 1024);
  EXPECT_NEAR(m.max_fx / 1024.0, logOdds(0.97), 0.5 / 1024);
  // A long mixed sequence: fixed point tracks the float update (clamped) within rounding.
  Cell c;
  double lf = 0.0;
  bool first = true;
  for (int i = 0; i < 200; ++i) {
    const bool hit = (i * 7919) % 5 < 2;
    m.apply(c, hit);
    lf = (first ? 0.0 : lf) + (hit ? logOdds(0.7) : logOdds(0.4));
    lf = std::min(std::max(lf, logOdds(0.12)), logOdds(0.97));
    first = false;
    EXPECT_NEAR(c.log_odds_fx / 1024.0, lf, 0.01) << "update " << i;
  }
}

TEST(OccupancyTest, ClampsAndCountsHits) {
  const OccupancyModel m = OccupancyModel::fromParams(OccupancyParams());
  Cell c;
  EXPECT_FALSE(c.observed());
  EXPECT_EQ(m.state(c), CellState::kUnknown);
  for (int i = 0; i < 50; ++i) m.apply(c, true);
  EXPECT_EQ(c.log_odds_fx, m.max_fx);
  EXPECT_EQ(c.hits, 50);
  EXPECT_NEAR(probabilityOf(c.log_odds_fx), 0.97, 1e-3);
  for (int i = 0; i < 50; ++i) m.apply(c, false);
  EXPECT_EQ(c.log_odds_fx, m.min_fx);
  EXPECT_EQ(c.hits, 50);
  Cell saturated;
  saturated.hits = INT16_MAX;
  m.apply(saturated, true);
  EXPECT_EQ(saturated.hits, INT16_MAX);
}

TEST(OccupancyTest, UnknownBandFollowsThePaper) {
  OccupancyParams p;  // band 0.05: unknown for 0.45 <= p <= 0.55
  const OccupancyModel m = OccupancyModel::fromParams(p);
  Cell c;
  c.log_odds_fx = logOddsFxOf(0.549);
  EXPECT_EQ(m.state(c), CellState::kUnknown);
  c.log_odds_fx = logOddsFxOf(0.56);
  EXPECT_EQ(m.state(c), CellState::kOccupied);
  c.log_odds_fx = logOddsFxOf(0.451);
  EXPECT_EQ(m.state(c), CellState::kUnknown);
  c.log_odds_fx = logOddsFxOf(0.44);
  EXPECT_EQ(m.state(c), CellState::kFree);
  // One hit or one miss leaves the band (OctoMap defaults).
  Cell h, f;
  m.apply(h, true);
  m.apply(f, false);
  EXPECT_EQ(m.state(h), CellState::kOccupied);
  EXPECT_EQ(m.state(f), CellState::kFree);
  // Band 0 is OctoMap's rule: occupied iff p > 0.5.
  p.unknown_band = 0.0;
  const OccupancyModel o = OccupancyModel::fromParams(p);
  c.log_odds_fx = 0;
  EXPECT_EQ(o.state(c), CellState::kFree);
  c.log_odds_fx = 1;
  EXPECT_EQ(o.state(c), CellState::kOccupied);
}

TEST(OccupancyTest, RejectsBadParameters) {
  OccupancyParams p;
  p.prob_hit = 0.4;
  EXPECT_THROW(p.validate(), InvalidArgument);
  p = OccupancyParams();
  p.clamp_min = 0.99;
  EXPECT_THROW(p.validate(), InvalidArgument);
  p = OccupancyParams();
  p.prob_miss = std::nan("");
  EXPECT_THROW(OccupancyModel::fromParams(p), InvalidArgument);
  p = OccupancyParams();
  p.unknown_band = 0.5;
  EXPECT_THROW(p.validate(), InvalidArgument);
}

}  // namespace
}  // namespace fragg
