// Map::merge: add of maps built from disjoint halves of a scan set against the map of all
// scans, whole-voxel translations (exact key shifts) and a resampled rotation (against a
// brute-force nearest-cell expectation).
#include <gtest/gtest.h>

#include <cstdio>

#include "submap_scenes.h"

namespace fragg {
namespace {

using test::cellAt;
using test::forEachObserved;
using test::sameCell;

struct AddComparison {
  size_t cells = 0;      ///< observed in the full map or the sum
  size_t equal = 0;      ///< same log-odds and hits
  size_t unclamped = 0;  ///< neither half nor the full map at a clamping bound
  size_t unclamped_equal = 0;
};

/// The merged (halves added) map against the full one, cell by cell.
AddComparison compareAdd(const Map& merged, const Map& full, const Map& a, const Map& b) {
  const OccupancyModel& m = full.model();
  auto atBound = [&](const Cell& c) {
    return c.observed() && (c.log_odds_fx == m.min_fx || c.log_odds_fx == m.max_fx);
  };
  AddComparison out;
  auto visit = [&](const VoxelKey& k) {
    const Cell cm = cellAt(merged, k), cf = cellAt(full, k);
    ++out.cells;
    const bool equal = sameCell(cm, cf);
    out.equal += equal ? 1 : 0;
    if (!atBound(cf) && !atBound(cellAt(a, k)) && !atBound(cellAt(b, k))) {
      ++out.unclamped;
      out.unclamped_equal += equal ? 1 : 0;
    }
  };
  forEachObserved(full, [&](const VoxelKey& k, const Cell&) { visit(k); });
  forEachObserved(merged, [&](const VoxelKey& k, const Cell&) {
    if (!cellAt(full, k).observed()) visit(k);
  });
  return out;
}

void expectAddOfHalves(const std::vector<int>& half_a, const std::vector<int>& half_b,
                       const std::vector<int>& all, double min_equal_share, const char* label) {
  const Map a = test::rgbdMap(half_a), b = test::rgbdMap(half_b), full = test::rgbdMap(all);
  Map merged = test::rgbdMap(half_a);
  const SubmapStats st = merged.merge(b, MergeMode::kAdd);
  EXPECT_EQ(st.cells, b.knownVoxelCount());
  const AddComparison c = compareAdd(merged, full, a, b);
  const double share = double(c.equal) / double(c.cells);
  std::printf(
      "[merge add] %s: %zu cells, %.4f %% equal to the map of all frames; %zu cells where no "
      "clamping bound was met, %zu of them equal\n",
      label, c.cells, 100.0 * share, c.unclamped, c.unclamped_equal);
  EXPECT_GT(c.cells, 100000u);
  EXPECT_EQ(c.unclamped_equal, c.unclamped);
  EXPECT_GE(share, min_equal_share);
}

TEST(MergeAddTest, HalvesOfFourRealFramesAddUpToTheFullMap) {
  // Two updates per half, four in all: no cell can meet a clamping bound (4 hits: 3,468 <
  // 3,476; 4 misses: -1,660 > -2,036), so the sum is the full map everywhere.
  expectAddOfHalves({0, 2}, {1, 3}, {0, 1, 2, 3}, 1.0, "frames {0,2} + {1,3}");
}

TEST(MergeAddTest, HalvesOfFiveRealFramesAddUpWhereNoClampWasMet) {
  // Five misses (-2,075) or five hits (4,335) pass a bound: those cells of the full map are
  // clamped while the sum of the halves is clamped once at the end; the same bound, so the
  // cells still agree. (Measured: every cell equal.)
  expectAddOfHalves({0, 2, 4}, {1, 3}, {0, 1, 2, 3, 4}, 0.9999, "frames {0,2,4} + {1,3}");
}

TEST(MergeAddTest, AddClampsAndSaturatesHits) {
  Map map(test::cpuParams()), sub(test::cpuParams());
  const OccupancyModel& m = map.model();
  map.writeCells([&](CellWriter& w) {
    w.set({0, 0, 0}, Cell{30000, static_cast<int16_t>(m.max_fx - 10)});
    w.set({1, 0, 0}, Cell{0, static_cast<int16_t>(m.min_fx + 5)});
    w.set({2, 0, 0}, Cell{3, 100});
  });
  sub.writeCells([&](CellWriter& w) {
    w.set({0, 0, 0}, Cell{30000, 500});
    w.set({1, 0, 0}, Cell{0, -400});
    w.set({3, 0, 0}, Cell{2, -50});  // unobserved in the map: taken as it is
  });
  map.merge(sub, MergeMode::kAdd);
  EXPECT_TRUE(sameCell(cellAt(map, {0, 0, 0}), Cell{INT16_MAX, m.max_fx}));
  EXPECT_TRUE(sameCell(cellAt(map, {1, 0, 0}), Cell{0, m.min_fx}));
  EXPECT_TRUE(sameCell(cellAt(map, {2, 0, 0}), Cell{3, 100}));  // unobserved in the sub-map
  EXPECT_TRUE(sameCell(cellAt(map, {3, 0, 0}), Cell{2, -50}));
  // Overwrite: observed sub cells replace, the rest stays.
  Map over(test::cpuParams());
  over.writeCells([&](CellWriter& w) {
    w.set({0, 0, 0}, Cell{1, 10});
    w.set({2, 0, 0}, Cell{3, 100});
  });
  over.merge(sub, MergeMode::kOverwrite);
  EXPECT_TRUE(sameCell(cellAt(over, {0, 0, 0}), Cell{30000, 500}));
  EXPECT_TRUE(sameCell(cellAt(over, {2, 0, 0}), Cell{3, 100}));
  EXPECT_TRUE(sameCell(cellAt(over, {3, 0, 0}), Cell{2, -50}));
}

TEST(MergeTransformTest, WholeVoxelTranslationIsAnExactKeyShift) {
  const Map sub = test::roomMap();
  const double res = sub.resolution();
  const VoxelKey shift{3, -2, 17};
  // Off the grid by 1e-8 of a voxel: still a whole-cell translation.
  Eigen::Isometry3d T_map_sub = Eigen::Isometry3d::Identity();
  T_map_sub.translation() =
      (Eigen::Vector3d(shift.x, shift.y, shift.z) + Eigen::Vector3d::Constant(1e-8)) * res;
  Map map(test::cpuParams());
  const SubmapStats st = map.merge(sub, MergeMode::kOverwrite, T_map_sub);
  EXPECT_EQ(st.cells, sub.knownVoxelCount());
  EXPECT_EQ(map.knownVoxelCount(), sub.knownVoxelCount());
  size_t checked = 0;
  forEachObserved(sub, [&](const VoxelKey& k, const Cell& c) {
    ASSERT_TRUE(sameCell(cellAt(map, {k.x + shift.x, k.y + shift.y, k.z + shift.z}), c));
    ++checked;
  });
  EXPECT_GT(checked, 100000u);
  // And back by the inverse: the original map.
  Map back(test::cpuParams());
  back.merge(map, MergeMode::kOverwrite, T_map_sub.inverse());
  std::string why;
  EXPECT_TRUE(test::sameCells(back, sub, &why)) << why;
}

TEST(MergeTransformTest, RotationIsResampledFromTheNearestCell) {
  const Map sub = test::roomMap(test::cpuParams(0.1));
  Eigen::Isometry3d T_map_sub = Eigen::Isometry3d::Identity();
  T_map_sub.linear() = (Eigen::AngleAxisd(0.5, Eigen::Vector3d::UnitZ()) *
                        Eigen::AngleAxisd(0.1, Eigen::Vector3d::UnitX()))
                           .toRotationMatrix();
  T_map_sub.translation() = Eigen::Vector3d(1.234, -0.567, 0.089);
  Map map(test::cpuParams(0.1));
  map.merge(sub, MergeMode::kOverwrite, T_map_sub);

  // Brute force: every cell of a box around the transformed sub-map takes the sub-map cell
  // containing its centre mapped back.
  const KeyBounds b = sub.bounds();
  const Eigen::Isometry3d T_sub_map = T_map_sub.inverse();
  Eigen::Vector3d lo = Eigen::Vector3d::Constant(1e9), hi = -lo;
  for (int corner = 0; corner < 8; ++corner) {
    const Eigen::Vector3d p((corner & 1) ? b.max.x + 1 : b.min.x,
                            (corner & 2) ? b.max.y + 1 : b.min.y,
                            (corner & 4) ? b.max.z + 1 : b.min.z);
    const Eigen::Vector3d q = T_map_sub * (p * sub.resolution());
    lo = lo.cwiseMin(q);
    hi = hi.cwiseMax(q);
  }
  const VoxelKey klo = map.keyOf(lo), khi = map.keyOf(hi);
  size_t expected_observed = 0;
  for (int32_t z = klo.z - 2; z <= khi.z + 2; ++z)
    for (int32_t y = klo.y - 2; y <= khi.y + 2; ++y)
      for (int32_t x = klo.x - 2; x <= khi.x + 2; ++x) {
        const VoxelKey v{x, y, z};
        const Cell want = cellAt(sub, sub.keyOf(T_sub_map * map.centerOf(v)));
        expected_observed += want.observed() ? 1 : 0;
        ASSERT_TRUE(sameCell(cellAt(map, v), want)) << x << " " << y << " " << z;
      }
  EXPECT_EQ(map.knownVoxelCount(), expected_observed);
  EXPECT_GT(expected_observed, 10000u);
}

}  // namespace
}  // namespace fragg
