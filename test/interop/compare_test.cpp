// Map comparison figures on hand-made maps.
#include "fragg_map/interop/compare.h"

#include <gtest/gtest.h>

#include <cmath>

#include "fragg_map/errors.h"
#include "interop_test_util.h"

namespace fragg {
namespace {

using test::paramsAt;
using test::setCell;

constexpr CellState kU = CellState::kUnknown;
constexpr CellState kF = CellState::kFree;
constexpr CellState kO = CellState::kOccupied;

struct Pair {
  Map a{paramsAt(0.05)};
  Map b{paramsAt(0.05)};
};

/// One cell per situation (fx values; kUnobservedLogOdds = not set):
///   1 free/free  2 occupied/occupied  3 free/occupied  4 occupied/unobserved
///   5 unobserved/free (a block a does not have)  6 in-band (+50)/free
///   7 unobserved in both (inside blocks both have)  8 in-band (-40)/in-band (+60)
///   9 exactly p = 0.5 / free
Pair samplePair() {
  Pair p;
  const int16_t occ = p.a.model().max_fx, free = p.a.model().min_fx;
  auto both = [&](VoxelKey k, int16_t fa, int16_t fb) {
    if (fa != kUnobservedLogOdds) setCell(p.a, k, fa);
    if (fb != kUnobservedLogOdds) setCell(p.b, k, fb);
  };
  both({0, 0, 0}, free, free);
  both({1, 0, 0}, occ, occ);
  both({2, 0, 0}, free, occ);
  both({3, 0, 0}, occ, kUnobservedLogOdds);
  both({100, 100, 100}, kUnobservedLogOdds, free);
  both({4, 0, 0}, 50, free);
  // cell 7: (5, 0, 0) lies in block (0, 0, 0), which both maps have; nobody sets it.
  both({6, 0, 0}, -40, 60);
  both({-1, -1, -1}, 0, free);
  return p;
}

TEST(Compare, OwnBandFigures) {
  const Pair p = samplePair();
  const MapComparison c = compareMaps(p.a, p.b);
  EXPECT_FALSE(c.octomap_threshold);
  EXPECT_EQ(c.count(kF, kF), 1u);
  EXPECT_EQ(c.count(kO, kO), 1u);
  EXPECT_EQ(c.count(kF, kO), 1u);
  EXPECT_EQ(c.count(kO, kU), 1u);
  EXPECT_EQ(c.count(kU, kF), 3u);  // cells 5, 6 and 9 (p = 0.5 is unknown with a band)
  EXPECT_EQ(c.count(kU, kU), 1u);  // cell 8: observed, but in the band in both
  EXPECT_EQ(c.count(kO, kF), 0u);
  EXPECT_EQ(c.count(kU, kO), 0u);
  EXPECT_EQ(c.count(kF, kU), 0u);
  EXPECT_EQ(c.known_in_a, 4u);
  EXPECT_EQ(c.known_in_b, 6u);
  EXPECT_EQ(c.known_in_both, 3u);
  EXPECT_EQ(c.known_in_either, 7u);
  EXPECT_EQ(c.agreeing, 2u);
  EXPECT_DOUBLE_EQ(c.agreementInBoth(), 2.0 / 3.0);
  EXPECT_DOUBLE_EQ(c.agreementInEither(), 2.0 / 7.0);
}

TEST(Compare, OctomapThresholdKnowsEveryObservedCell) {
  const Pair p = samplePair();
  CompareOptions options;
  options.octomap_threshold = true;
  const MapComparison c = compareMaps(p.a, p.b, options);
  EXPECT_TRUE(c.octomap_threshold);
  EXPECT_EQ(c.count(kF, kF), 1u);
  EXPECT_EQ(c.count(kO, kO), 1u);
  EXPECT_EQ(c.count(kF, kO), 2u);  // cells 3 and 8 (-40 free, +60 occupied)
  EXPECT_EQ(c.count(kO, kF), 2u);  // cell 6 (+50) and cell 9 (p = 0.5 is occupied)
  EXPECT_EQ(c.count(kO, kU), 1u);
  EXPECT_EQ(c.count(kU, kF), 1u);
  EXPECT_EQ(c.count(kU, kU), 0u);
  EXPECT_EQ(c.known_in_both, 6u);
  EXPECT_EQ(c.known_in_either, 8u);
  EXPECT_EQ(c.agreeing, 2u);
  EXPECT_DOUBLE_EQ(c.agreementInBoth(), 2.0 / 6.0);
  EXPECT_DOUBLE_EQ(c.agreementInEither(), 2.0 / 8.0);
}

TEST(Compare, ConfusionIsTransposedWhenTheMapsSwap) {
  const Pair p = samplePair();
  const MapComparison ab = compareMaps(p.a, p.b);
  const MapComparison ba = compareMaps(p.b, p.a);
  for (CellState x : {kU, kF, kO})
    for (CellState y : {kU, kF, kO}) EXPECT_EQ(ab.count(x, y), ba.count(y, x));
  EXPECT_EQ(ab.agreeing, ba.agreeing);
  EXPECT_EQ(ab.known_in_either, ba.known_in_either);
}

TEST(Compare, MapAgreesWithItself) {
  const Pair p = samplePair();
  const MapComparison c = compareMaps(p.b, p.b);
  EXPECT_EQ(c.known_in_both, c.known_in_either);
  EXPECT_EQ(c.agreeing, c.known_in_both);
  EXPECT_DOUBLE_EQ(c.agreementInBoth(), 1.0);
  EXPECT_DOUBLE_EQ(c.agreementInEither(), 1.0);
}

TEST(Compare, EmptyMapsHaveNoAgreementFigure) {
  const MapComparison c = compareMaps(Map(paramsAt(0.1)), Map(paramsAt(0.1)));
  EXPECT_EQ(c.known_in_either, 0u);
  EXPECT_TRUE(std::isnan(c.agreementInBoth()));
  EXPECT_TRUE(std::isnan(c.agreementInEither()));
}

TEST(Compare, DifferentResolutionsAreRejected) {
  EXPECT_THROW(compareMaps(Map(paramsAt(0.05)), Map(paramsAt(0.1))), InvalidArgument);
  // OctoMap files carry the resolution with 6 significant digits.
  EXPECT_NO_THROW(compareMaps(Map(paramsAt(1.0 / 30)), Map(paramsAt(0.0333333))));
}

}  // namespace
}  // namespace fragg
