// The ray pass walks past blocks whose every cell sits at the lower clamp (a miss changes
// nothing there). These tests build the same maps with the skip on and off, through inserts,
// removals, pose corrections and edits, and require the same bytes in every block, while the
// skip must visit fewer cells.
#include <gtest/gtest.h>

#include <cstdio>
#include <map>

#include "fragg_map/map.h"
#include "same_map.h"
#include "test_scenes.h"

namespace fragg {
namespace {

using test::expectSameMap;

MapParams paramsWithSkip(bool skip) {
  MapParams p;
  p.resolution_m = 0.05;
  p.skip_saturated_blocks = skip;
  p.scans.keep = true;  // removal and correction need the scans
  return p;
}

/// Blocks whose every cell is at the model's lower clamp.
size_t saturatedBlocks(const Map& m) {
  size_t n = 0;
  m.forEachBlock([&](const BlockKey&, const Block& block) {
    bool all = true;
    for (const Cell& c : block.cells) all &= c.log_odds_fx == m.model().min_fx;
    n += all;
  });
  return n;
}

Eigen::Isometry3d poseAt(int i) {
  Eigen::Isometry3d T = Eigen::Isometry3d::Identity();
  T.translation() = Eigen::Vector3d(0.013 * i - 0.2, 0.021 * (i % 5) - 0.05, 1.2 + 0.004 * i);
  T.rotate(Eigen::AngleAxisd(0.05 * i, Eigen::Vector3d::UnitZ()));
  return T;
}

struct Pair {
  Map on{paramsWithSkip(true)};
  Map off{paramsWithSkip(false)};
  uint64_t visits_on = 0, visits_off = 0;

  ScanId insert(const PointCloud& cloud, const Eigen::Isometry3d& T) {
    const InsertStats a = on.insert(cloud, T, SensorModel::autoFromCloud());
    const InsertStats b = off.insert(cloud, T, SensorModel::autoFromCloud());
    EXPECT_EQ(a.scan_id, b.scan_id);
    visits_on += a.voxel_visits;
    visits_off += b.voxel_visits;
    return a.scan_id;
  }
};

TEST(SaturatedSkipTest, SameMapWithFewerVisitsOverManyScans) {
  const PointCloud room = test::roomScan(3.0, 1.2, 1.5, 32, 360);
  Pair maps;
  for (int i = 0; i < 24; ++i) maps.insert(room, poseAt(i));
  expectSameMap(maps.on, maps.off, "24 scans");
  std::printf("visits with the skip %llu, without %llu; %zu of %zu blocks saturated\n",
              static_cast<unsigned long long>(maps.visits_on),
              static_cast<unsigned long long>(maps.visits_off), saturatedBlocks(maps.on),
              maps.on.blockCount());
  // The room's inside is seen often enough to reach the lower clamp in many blocks...
  EXPECT_GT(saturatedBlocks(maps.on), 50u);
  // ...and those are walked past: the skip must save a real share of the visits.
  EXPECT_LT(maps.visits_on, maps.visits_off * 9 / 10)
      << "with skip " << maps.visits_on << ", without " << maps.visits_off;
}

TEST(SaturatedSkipTest, RemovalCorrectionAndEditsKeepTheMapsEqual) {
  const PointCloud room = test::roomScan(3.0, 1.2, 1.5, 32, 360);
  Pair maps;
  std::vector<ScanId> ids;
  for (int i = 0; i < 14; ++i) ids.push_back(maps.insert(room, poseAt(i)));
  // A removal undoes misses in clamped blocks too (it never skips), then inserts skip again.
  const InsertStats r_on = maps.on.remove(ids[3]), r_off = maps.off.remove(ids[3]);
  EXPECT_EQ(r_on.voxel_visits, r_off.voxel_visits);
  expectSameMap(maps.on, maps.off, "after a removal");
  for (int i = 14; i < 18; ++i) maps.insert(room, poseAt(i));
  expectSameMap(maps.on, maps.off, "inserts after the removal");

  // Loop closure: move two scans (removed and re-inserted at the new poses).
  std::map<ScanId, Eigen::Isometry3d> moved;
  moved[ids[5]] = poseAt(30);
  moved[ids[9]] = poseAt(31);
  maps.on.correctPoses(moved);
  maps.off.correctPoses(moved);
  expectSameMap(maps.on, maps.off, "after a pose correction");

  // An edit inside saturated space: the flags of the cleared blocks must not survive it.
  const size_t saturated_before = saturatedBlocks(maps.on);
  ASSERT_GT(saturated_before, 5u);
  maps.on.clearBox(Eigen::Vector3d(-1.0, -1.0, 0.5), Eigen::Vector3d(1.0, 1.0, 2.0));
  maps.off.clearBox(Eigen::Vector3d(-1.0, -1.0, 0.5), Eigen::Vector3d(1.0, 1.0, 2.0));
  EXPECT_LT(saturatedBlocks(maps.on), saturated_before);
  for (int i = 18; i < 24; ++i) maps.insert(room, poseAt(i));
  expectSameMap(maps.on, maps.off, "inserts after clearing a box");

  // A merge that adds log-odds into saturated blocks (a sub-map cut from the map itself).
  const Map sub =
      maps.off.extract(Eigen::Vector3d(-2.0, -2.0, 0.0), Eigen::Vector3d(2.0, 2.0, 2.5));
  maps.on.merge(sub, MergeMode::kAdd);
  maps.off.merge(sub, MergeMode::kAdd);
  for (int i = 24; i < 28; ++i) maps.insert(room, poseAt(i));
  expectSameMap(maps.on, maps.off, "inserts after a merge");
}

}  // namespace
}  // namespace fragg
