// Map::extract / truncate / truncateOutside on a map of real RGB-D frames: each cell goes to
// exactly one side (brute force over every cell), and merging the sub-map back (overwrite)
// gives the original map bit for bit.
#include <gtest/gtest.h>

#include <functional>

#include "fragg_map/errors.h"
#include "submap_scenes.h"

namespace fragg {
namespace {

using test::cellAt;
using test::forEachObserved;
using test::sameCell;

/// A box through the middle of the map's bounds, corners off the voxel grid.
SubmapRegion middleBox(const Map& map) {
  const KeyBounds b = map.bounds();
  const Eigen::Vector3d lo = map.centerOf(b.min), hi = map.centerOf(b.max);
  const Eigen::Vector3d mid = 0.5 * (lo + hi);
  return SubmapRegion::box(mid - 0.3 * (hi - lo) + Eigen::Vector3d(0.013, -0.007, 0.021),
                           mid + Eigen::Vector3d(0.6, 0.5, 0.4).cwiseProduct(hi - lo) * 0.5);
}

/// Every observed cell of `original` is in `sub` where region holds and in `rest` elsewhere,
/// unchanged; neither holds any other observed cell.
void expectSplit(const Map& original, const Map& rest, const Map& sub,
                 const std::function<bool(const Eigen::Vector3d&)>& in_sub) {
  size_t in = 0, out = 0;
  forEachObserved(original, [&](const VoxelKey& k, const Cell& c) {
    const bool inside = in_sub(original.centerOf(k));
    const Cell s = cellAt(sub, k), r = cellAt(rest, k);
    if (inside) {
      ++in;
      ASSERT_TRUE(sameCell(s, c)) << k.x << " " << k.y << " " << k.z;
      ASSERT_FALSE(r.observed()) << k.x << " " << k.y << " " << k.z;
    } else {
      ++out;
      ASSERT_TRUE(sameCell(r, c)) << k.x << " " << k.y << " " << k.z;
      ASSERT_FALSE(s.observed()) << k.x << " " << k.y << " " << k.z;
    }
  });
  EXPECT_GT(in, 1000u);
  EXPECT_GT(out, 1000u);
  size_t extra = 0;
  forEachObserved(sub, [&](const VoxelKey& k, const Cell&) {
    extra += cellAt(original, k).observed() ? 0 : 1;
  });
  forEachObserved(rest, [&](const VoxelKey& k, const Cell&) {
    extra += cellAt(original, k).observed() ? 0 : 1;
  });
  EXPECT_EQ(extra, 0u);
  EXPECT_EQ(sub.knownVoxelCount() + rest.knownVoxelCount(), original.knownVoxelCount());
  // No block is left without an observed cell.
  for (const Map* m : {&rest, &sub})
    m->forEachBlock([&](const BlockKey&, const Block& b) {
      bool any = false;
      for (const Cell& c : b.cells) any |= c.observed();
      EXPECT_TRUE(any);
    });
}

TEST(TruncateTest, BoxSplitsRealMapAndMergeRestoresIt) {
  const Map original = test::rgbdMap({0, 1, 2, 3, 4});
  Map map = test::rgbdMap({0, 1, 2, 3, 4});
  ASSERT_TRUE(test::sameCells(map, original));
  const SubmapRegion box = middleBox(map);
  const uint64_t rev = map.revision();
  SubmapStats st;
  const Map sub = map.truncate(box.min_map, box.max_map, Backend::kCpu, &st);
  EXPECT_GT(map.revision(), rev);
  EXPECT_EQ(sub.region().kind, SubmapRegion::Kind::kBox);
  EXPECT_EQ(sub.region().min_map, box.min_map);
  EXPECT_EQ(sub.region().max_map, box.max_map);
  EXPECT_EQ(sub.resolution(), map.resolution());
  EXPECT_EQ(sub.scanStore().size(), 0u);
  EXPECT_EQ(st.cells, sub.knownVoxelCount());
  EXPECT_EQ(st.blocks, sub.blockCount());
  expectSplit(original, map, sub, [&](const Eigen::Vector3d& p) {
    return (p.array() >= box.min_map.array()).all() && (p.array() <= box.max_map.array()).all();
  });
  // Blocks the truncation changed are listed for incremental readers.
  EXPECT_FALSE(map.changedBlocksSince(rev).empty());

  const SubmapStats merged = map.merge(sub, MergeMode::kOverwrite);
  EXPECT_EQ(merged.cells, sub.knownVoxelCount());
  std::string why;
  EXPECT_TRUE(test::sameCells(map, original, &why)) << why;
}

TEST(TruncateTest, ExtractCopiesWithoutChangingTheMap) {
  Map map = test::roomMap();
  const Map copy = test::roomMap();
  const SubmapRegion box = middleBox(map);
  const uint64_t rev = map.revision();
  const Map sub = map.extract(box.min_map, box.max_map);
  EXPECT_EQ(map.revision(), rev);
  EXPECT_TRUE(test::sameCells(map, copy));
  Map cut = test::roomMap();
  const Map truncated = cut.truncate(box.min_map, box.max_map);
  std::string why;
  EXPECT_TRUE(test::sameCells(sub, truncated, &why)) << why;
}

TEST(TruncateTest, ExtractOutsideCopiesWhatTruncateOutsideMoves) {
  Map map = test::roomMap();
  const Map copy = test::roomMap();
  const KeyBounds b = map.bounds();
  const Eigen::Vector3d centre = 0.5 * (map.centerOf(b.min) + map.centerOf(b.max));
  const double radius_m = 0.3 * (map.centerOf(b.max) - map.centerOf(b.min)).norm();
  const uint64_t rev = map.revision();
  const Map sub = map.extractOutside(centre, radius_m);
  EXPECT_EQ(map.revision(), rev);
  EXPECT_TRUE(test::sameCells(map, copy));
  EXPECT_EQ(sub.region().kind, SubmapRegion::Kind::kOutsideSphere);
  EXPECT_GT(sub.knownVoxelCount(), 1000u);
  Map cut = test::roomMap();
  const Map moved = cut.truncateOutside(centre, radius_m);
  std::string why;
  EXPECT_TRUE(test::sameCells(sub, moved, &why)) << why;
  EXPECT_THROW(map.extractOutside(centre, -1.0), InvalidArgument);
}

TEST(TruncateTest, OutsideRadiusSplitsRealMapAndMergeRestoresIt) {
  const Map original = test::rgbdMap({0, 1, 2, 3, 4});
  Map map = test::rgbdMap({0, 1, 2, 3, 4});
  const KeyBounds b = map.bounds();
  const Eigen::Vector3d centre =
      0.5 * (map.centerOf(b.min) + map.centerOf(b.max)) + Eigen::Vector3d(0.011, 0.03, -0.02);
  const double radius_m = 0.35 * (map.centerOf(b.max) - map.centerOf(b.min)).norm();
  const Map sub = map.truncateOutside(centre, radius_m);
  EXPECT_EQ(sub.region().kind, SubmapRegion::Kind::kOutsideSphere);
  EXPECT_EQ(sub.region().radius_m, radius_m);
  expectSplit(original, map, sub,
              [&](const Eigen::Vector3d& p) { return (p - centre).norm() > radius_m; });
  map.merge(sub, MergeMode::kOverwrite);
  std::string why;
  EXPECT_TRUE(test::sameCells(map, original, &why)) << why;
}

TEST(TruncateTest, BoxOutsideTheMapMovesNothingAndHugeBoxMovesAll) {
  Map map = test::roomMap();
  const size_t known = map.knownVoxelCount();
  const Map none = map.truncate(Eigen::Vector3d(100, 100, 100), Eigen::Vector3d(101, 101, 101));
  EXPECT_EQ(none.knownVoxelCount(), 0u);
  EXPECT_EQ(map.knownVoxelCount(), known);
  // Corners far beyond the key range are clamped to it, not refused.
  const Map all = map.truncate(Eigen::Vector3d::Constant(-1e30), Eigen::Vector3d::Constant(1e30));
  EXPECT_EQ(all.knownVoxelCount(), known);
  EXPECT_EQ(map.blockCount(), 0u);
  EXPECT_EQ(map.knownVoxelCount(), 0u);
}

TEST(TruncateTest, KeptScansReachingTheRegionBecomeUnremovable) {
  MapParams p = test::cpuParams();
  p.scans.keep = true;
  Map map(p);
  // Two scans 30 m apart (10 m range): a box at the first touches only the first.
  map.insert(test::roomScan(4.0, 1.0, 2.0, 16, 360), test::poseAt(0), test::lidar());
  Eigen::Isometry3d far = test::poseAt(0);
  far.translation().x() += 30.0;
  map.insert(test::roomScan(4.0, 1.0, 2.0, 16, 360), far, test::lidar());
  map.truncate(Eigen::Vector3d(-1, -1, -1), Eigen::Vector3d(1, 1, 1));
  EXPECT_FALSE(map.scanStore().record(0).removable);
  EXPECT_TRUE(map.scanStore().record(1).removable);
  EXPECT_THROW(map.remove(0), InvalidArgument);
  // Outside a 5 m sphere around the second scan: the first scan's rays reach there (already
  // marked), the second's (10 m + margin) too.
  map.truncateOutside(far.translation(), 5.0);
  EXPECT_FALSE(map.scanStore().record(1).removable);
}

TEST(TruncateTest, MergingMarksKeptScansReachingTheMergedRegion) {
  MapParams p = test::cpuParams();
  p.scans.keep = true;
  Map map(p);
  map.insert(test::roomScan(4.0, 1.0, 2.0, 16, 360), test::poseAt(0), test::lidar());
  Map sub(test::cpuParams());
  sub.writeCells([](CellWriter& w) { w.set(VoxelKey{2000, 0, 0}, Cell{1, 500}); });  // 100 m off
  map.merge(sub, MergeMode::kAdd);
  EXPECT_TRUE(map.scanStore().record(0).removable);
  sub.writeCells([](CellWriter& w) { w.set(VoxelKey{10, 0, 0}, Cell{1, 500}); });  // 0.5 m
  map.merge(sub, MergeMode::kAdd);
  EXPECT_FALSE(map.scanStore().record(0).removable);
}

}  // namespace
}  // namespace fragg
