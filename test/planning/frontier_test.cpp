// Frontier cells against a brute force over every cell and every neighbour (random and
// simulated maps, with and without filters), the incremental tracker against full recomputes
// after every scan of a W1-like drive, clusters and ids, gains against a brute-force ray
// count, and bad arguments.
#include <gtest/gtest.h>

#include <algorithm>
#include <array>
#include <atomic>
#include <cmath>
#include <limits>
#include <map>
#include <random>
#include <set>

#include "fragg_map/errors.h"
#include "fragg_map/geometry/mesh_bvh.h"
#include "fragg_map/io/dataset.h"
#include "fragg_map/planning/coarse_map.h"
#include "fragg_map/planning/frontier_cells.h"
#include "fragg_map/planning/frontier_clusters.h"
#include "fragg_map/planning/frontier_tracker.h"
#include "fragg_map/planning/query_control.h"
#include "fragg_map/planning/viewpoints.h"
#include "fragg_map/sim/lidar_sensor.h"
#include "fragg_map/sim/scene.h"
#include "fragg_map/sim/trajectory.h"
#include "gain_walk.h"
#include "planning/collision_reference.h"

namespace fragg::planning::test {
namespace {

bool unknownAt(const Map& map, const VoxelKey& k) {
  const Cell* c = map.findCell(k);
  return !c || map.state(*c) == CellState::kUnknown;
}

// Every observed cell, every one of its 26 neighbours, the filter written out again.
std::vector<VoxelKey> bruteForceFrontiers(const Map& map, const FrontierFilter& f = {}) {
  std::vector<VoxelKey> out;
  map.forEachBlock([&](const BlockKey& b, const Block& block) {
    for (int i = 0; i < kCellsPerBlock; ++i) {
      if (map.state(block.cells[i]) != CellState::kFree) continue;
      const VoxelKey k = voxelKeyOf(b, i);
      bool frontier = false;
      for (int dz = -1; dz <= 1 && !frontier; ++dz)
        for (int dy = -1; dy <= 1 && !frontier; ++dy)
          for (int dx = -1; dx <= 1 && !frontier; ++dx)
            if ((dx || dy || dz) && unknownAt(map, {k.x + dx, k.y + dy, k.z + dz})) frontier = true;
      if (!frontier) continue;
      const Eigen::Vector3d c = map.centerOf(k);
      if (f.use_box &&
          !(c.x() >= f.box_min_m.x() && c.y() >= f.box_min_m.y() && c.z() >= f.box_min_m.z() &&
            c.x() <= f.box_max_m.x() && c.y() <= f.box_max_m.y() && c.z() <= f.box_max_m.z()))
        continue;
      if (f.use_height && !(c.z() >= f.min_z_m && c.z() <= f.max_z_m)) continue;
      bool near = false;
      if (f.min_obstacle_distance_m > 0.0)
        map.forEachBlock([&](const BlockKey& ob, const Block& oblock) {
          for (int j = 0; j < kCellsPerBlock && !near; ++j)
            if (map.state(oblock.cells[j]) == CellState::kOccupied &&
                (map.centerOf(voxelKeyOf(ob, j)) - c).norm() <
                    f.min_obstacle_distance_m - 1e-9 * map.resolution())
              near = true;
        });
      if (!near) out.push_back(k);
    }
  });
  std::sort(out.begin(), out.end(), frontierOrder);
  return out;
}

// A real scan (PCL's room scan, 5 cm): the set, and the set under a box and a height band,
// equal the brute force; the tracker built from the scan cut in two (incremental) too.
TEST(FrontierCells, MatchBruteForceOnARealScan) {
  MapParams p;
  p.resolution_m = 0.05;
  p.backend = Backend::kCpu;
  Map map(p);
  auto source = openDataset(std::string(FRAGG_REAL_DATA) + "/pcl_room_scans/room_scan1.pcd");
  Scan scan;
  ASSERT_TRUE(source->next(scan));
  FrontierTracker tracker;
  PointCloud first_half, second_half;
  for (size_t i = 0; i < scan.cloud.size(); ++i)
    (i % 2 ? second_half : first_half).points_S.push_back(scan.cloud.points_S[i]);
  const SensorModel sensor = SensorModel::autoFromCloud();
  map.insert(first_half, scan.T_map_sensor, sensor);
  EXPECT_TRUE(tracker.update(map).full);
  map.insert(second_half, scan.T_map_sensor, sensor);
  EXPECT_FALSE(tracker.update(map).full);
  const std::vector<VoxelKey> expected = bruteForceFrontiers(map);
  ASSERT_GT(expected.size(), 1000u);
  EXPECT_EQ(findFrontierCells(map), expected);
  EXPECT_EQ(tracker.cells(), expected);
  FrontierFilter f;
  f.use_box = true;
  const Eigen::Vector3d lo = map.centerOf(map.bounds().min), hi = map.centerOf(map.bounds().max);
  f.box_min_m = lo + 0.25 * (hi - lo);
  f.box_max_m = lo + 0.75 * (hi - lo);
  f.use_height = true;
  f.min_z_m = lo.z() + 0.3 * (hi.z() - lo.z());
  f.max_z_m = hi.z();
  const std::vector<VoxelKey> filtered = bruteForceFrontiers(map, f);
  ASSERT_GT(filtered.size(), 10u);
  ASSERT_LT(filtered.size(), expected.size());
  EXPECT_EQ(findFrontierCells(map, f), filtered);
}

TEST(FrontierCells, MatchBruteForceOnRandomMaps) {
  for (uint32_t seed : {1u, 2u, 3u}) {
    const Map map = randomMap(0.1, 16, seed);
    const auto expected = bruteForceFrontiers(map);
    ASSERT_GT(expected.size(), 100u);
    EXPECT_EQ(findFrontierCells(map), expected) << "seed " << seed;
    EXPECT_EQ(findFrontierCells(map, {}, 1), expected) << "one thread, seed " << seed;
  }
}

TEST(FrontierCells, FiltersMatchBruteForce) {
  const Map map = randomMap(0.1, 16, 7);
  FrontierFilter box;
  box.use_box = true;
  box.box_min_m = Eigen::Vector3d(-0.75, -1.0, -0.3);
  box.box_max_m = Eigen::Vector3d(0.55, 0.4, 1.0);
  FrontierFilter band;
  band.use_height = true;
  band.min_z_m = -0.5;
  band.max_z_m = 0.25;
  FrontierFilter distance;
  distance.min_obstacle_distance_m = 0.25;
  for (const FrontierFilter& f : {box, band, distance}) {
    const auto expected = bruteForceFrontiers(map, f);
    ASSERT_FALSE(expected.empty());
    ASSERT_LT(expected.size(), bruteForceFrontiers(map).size()) << "the filter must drop some";
    EXPECT_EQ(findFrontierCells(map, f), expected);
  }
}

TEST(FrontierCells, CrossBlockBordersAndMissingBlocks) {
  MapParams p;
  p.resolution_m = 0.1;
  Map map(p);
  // A free slab filling block (0,0,0) exactly; everything around it has no block.
  map.writeCells([&](CellWriter& w) {
    for (int z = 0; z < 8; ++z)
      for (int y = 0; y < 8; ++y)
        for (int x = 0; x < 8; ++x) w.set({x, y, z}, Cell{0, -2000});
  });
  auto cells = findFrontierCells(map);
  EXPECT_EQ(cells.size(), 512u - 6u * 6u * 6u) << "the block's surface cells";
  // A free neighbour block on +x: the shared face stops being a frontier.
  map.writeCells([&](CellWriter& w) {
    for (int z = 0; z < 8; ++z)
      for (int y = 0; y < 8; ++y)
        for (int x = 8; x < 16; ++x) w.set({x, y, z}, Cell{0, -2000});
  });
  cells = findFrontierCells(map);
  EXPECT_EQ(cells, bruteForceFrontiers(map));
  EXPECT_EQ(std::count_if(cells.begin(), cells.end(),
                          [](const VoxelKey& k) { return k.x == 7 || k.x == 8; }),
            2 * 64 - 2 * 36)
      << "only the rims of the inner faces stay frontier";
}

// A W1-like drive (the campus street, LiDAR at 1.8 m) with fewer beams than W1 so that 100
// scans stay quick; the tracker after each scan equals a full recompute.
TEST(FrontierTracker, IncrementalEqualsFullOverAHundredScans) {
  sim::Scene scene = sim::loadScene(std::string(FRAGG_SOURCE_DIR) + "/config/scenes/campus.json");
  const sim::Terrain terrain = scene.terrain;
  const auto poses = sim::sampleTrajectory(
      scene.trajectories.at("street"),
      [&terrain](double x, double y) { return terrain.heightAt(x, y); }, sim::DriftSpec(), 101,
      100);
  const geometry::MeshBvh bvh(std::move(scene.mesh));
  sim::LidarSpec spec;
  spec.beams = 16;
  spec.azimuth_steps = 360;
  spec.elevation_min_deg = -25;
  spec.elevation_max_deg = 15;
  spec.max_range_m = 80;
  Eigen::Isometry3d T_base_sensor = Eigen::Isometry3d::Identity();
  T_base_sensor.translation().z() = 1.8;

  MapParams p;
  p.resolution_m = 0.2;
  Map map(p);
  FrontierTracker tracker;
  FrontierFilter band;
  band.use_height = true;
  band.min_z_m = 0.0;
  band.max_z_m = 3.0;
  FrontierTracker banded(band);
  const SensorModel sensor = SensorModel::autoFromCloud(0.0, 30.0);
  uint64_t incremental_updates = 0;
  for (size_t i = 0; i < poses.size(); ++i) {
    const Eigen::Isometry3d T = poses[i].T_map_base * T_base_sensor;
    map.insert(sim::simulateLidar(bvh, spec, T, 101, i), T, sensor);
    const FrontierUpdateStats st = tracker.update(map);
    banded.update(map);
    if (!st.full) ++incremental_updates;
    if (i % 10 == 9 || i < 3) {  // full recomputes are the slow part
      ASSERT_EQ(tracker.cells(), findFrontierCells(map)) << "after scan " << i;
      ASSERT_EQ(banded.cells(), findFrontierCells(map, band)) << "after scan " << i;
    }
  }
  EXPECT_EQ(incremental_updates, poses.size() - 1);
  EXPECT_GT(tracker.size(), 1000u);
  // Erasing blocks (clear box) forces a full recompute; the set stays exact.
  const Eigen::Vector3d c = poses[50].T_map_base.translation();
  map.clearBox(c - Eigen::Vector3d(4, 4, 1), c + Eigen::Vector3d(4, 4, 3));
  EXPECT_TRUE(tracker.update(map).full);
  EXPECT_EQ(tracker.cells(), findFrontierCells(map));
  // The brute force agrees on this real-looking map too.
  EXPECT_EQ(tracker.cells(), bruteForceFrontiers(map));
}

// collect() under the lock and apply() without it (the server's frontier topics): the same set
// as update() on the same map after every scan of a short drive, under a box filter too; a
// clear box makes it a full copy; a pair broken by another update, and a filter that reads
// cells, are refused.
TEST(FrontierTracker, CollectThenApplyEqualsUpdate) {
  sim::Scene scene = sim::loadScene(std::string(FRAGG_SOURCE_DIR) + "/config/scenes/campus.json");
  const sim::Terrain terrain = scene.terrain;
  const auto poses = sim::sampleTrajectory(
      scene.trajectories.at("street"),
      [&terrain](double x, double y) { return terrain.heightAt(x, y); }, sim::DriftSpec(), 7, 15);
  const geometry::MeshBvh bvh(std::move(scene.mesh));
  sim::LidarSpec spec;
  spec.beams = 16;
  spec.azimuth_steps = 360;
  spec.max_range_m = 60;
  Eigen::Isometry3d T_base_sensor = Eigen::Isometry3d::Identity();
  T_base_sensor.translation().z() = 1.8;
  MapParams p;
  p.resolution_m = 0.2;
  Map map(p);
  FrontierFilter box;
  box.use_box = true;
  box.box_min_m = poses[0].T_map_base.translation() - Eigen::Vector3d(20, 20, 1);
  box.box_max_m = poses[0].T_map_base.translation() + Eigen::Vector3d(20, 20, 4);
  FrontierTracker updated, copied, updated_box(box), copied_box(box);
  const SensorModel sensor = SensorModel::autoFromCloud(0.0, 30.0);
  uint64_t incremental = 0;
  for (size_t i = 0; i < poses.size(); ++i) {
    const Eigen::Isometry3d T = poses[i].T_map_base * T_base_sensor;
    map.insert(sim::simulateLidar(bvh, spec, T, 7, i), T, sensor);
    updated.update(map);
    updated_box.update(map);
    const FrontierMapChanges changes = copied.collect(map);
    EXPECT_EQ(changes.full, i == 0) << "scan " << i;
    const FrontierUpdateStats st = copied.apply(changes);
    copied_box.apply(copied_box.collect(map));
    if (!st.full) ++incremental;
    ASSERT_EQ(copied.cells(), updated.cells()) << "after scan " << i;
    ASSERT_EQ(copied_box.cells(), updated_box.cells()) << "after scan " << i;
    EXPECT_EQ(copied.revision(), map.revision());
  }
  EXPECT_EQ(incremental, poses.size() - 1);
  EXPECT_GT(copied.size(), 1000u);
  EXPECT_EQ(copied_box.cells(), findFrontierCells(map, box));
  // Nothing changed: an empty incremental copy, the set unchanged.
  const FrontierMapChanges none = copied.collect(map);
  EXPECT_FALSE(none.full);
  EXPECT_TRUE(none.keys.empty());
  EXPECT_EQ(copied.apply(none).cells, updated.size());
  // Blocks erased: a full copy of every block's masks; the set stays exact.
  const Eigen::Vector3d c = poses[12].T_map_base.translation();
  map.clearBox(c - Eigen::Vector3d(4, 4, 1), c + Eigen::Vector3d(4, 4, 3));
  const FrontierMapChanges after_clear = copied.collect(map);
  EXPECT_TRUE(after_clear.full);
  EXPECT_EQ(after_clear.keys.size(), map.blockCount());
  copied.apply(after_clear);
  EXPECT_EQ(copied.cells(), findFrontierCells(map));
  // A pair broken by an update in between is refused, the set untouched.
  const Eigen::Isometry3d T = poses[0].T_map_base * T_base_sensor;
  map.insert(sim::simulateLidar(bvh, spec, T, 7, 99), T, sensor);
  const FrontierMapChanges stale = copied.collect(map);
  ASSERT_FALSE(stale.full);
  copied.update(map);
  const std::vector<VoxelKey> before = copied.cells();
  EXPECT_THROW(copied.apply(stale), InvalidArgument);
  EXPECT_EQ(copied.cells(), before);
  // The obstacle distance filter reads cells: collect() refuses it.
  FrontierFilter near;
  near.min_obstacle_distance_m = 0.5;
  EXPECT_THROW((void)FrontierTracker(near).collect(map), InvalidArgument);
}

TEST(FrontierClusters, ComponentsSplitsDropsAndStableIds) {
  MapParams p;
  p.resolution_m = 0.1;
  Map map(p);
  // Free lines along x in unknown space: A of 40 cells, B of 8 cells, C of 3 cells.
  map.writeCells([&](CellWriter& w) {
    for (int x = 0; x < 40; ++x) w.set({x, 0, 0}, Cell{0, -2000});
    for (int x = 0; x < 8; ++x) w.set({x, 50, 0}, Cell{0, -2000});
    for (int x = 100; x < 103; ++x) w.set({x, 0, 0}, Cell{0, -2000});
  });
  const auto cells = findFrontierCells(map);
  ASSERT_EQ(cells.size(), 51u);
  ClusterOptions o;
  o.min_cells = 5;
  o.max_extent_m = 1.5;  // 15 cells: A is split into pieces of <= 15
  FrontierClusterer clusterer(o);
  const auto clusters = clusterer.cluster(map, cells);
  // A: 40 -> 20 + 20 -> 4 x 10 (ordered by x), then B; C is dropped.
  ASSERT_EQ(clusters.size(), 5u);
  std::set<uint64_t> ids;
  for (int i = 0; i < 4; ++i) {
    const auto& c = clusters[i];
    EXPECT_EQ(c.cells.size(), 10u);
    EXPECT_NEAR(c.min_m.x(), 1.0 * i, 1e-9);
    EXPECT_NEAR(c.max_m.x(), 1.0 * i + 1.0, 1e-9);
    EXPECT_NEAR(c.centroid_m.x(), 1.0 * i + 0.5, 1e-9);
    EXPECT_NEAR(c.centroid_m.y(), 0.05, 1e-9);
    ids.insert(c.id);
  }
  // Unknown all around a line cancels out, except past its ends.
  EXPECT_TRUE(clusters[0].direction.isApprox(Eigen::Vector3d(-1, 0, 0), 1e-9));
  EXPECT_NEAR(clusters[1].direction.norm(), 0.0, 1e-9);
  EXPECT_TRUE(clusters[3].direction.isApprox(Eigen::Vector3d(1, 0, 0), 1e-9));
  EXPECT_EQ(clusters[4].cells.size(), 8u);
  EXPECT_NEAR(clusters[4].centroid_m.y(), 5.05, 1e-9);
  ids.insert(clusters[4].id);
  EXPECT_EQ(ids.size(), 5u);
  // Same cells again: same ids. B changed: only B gets a new id.
  const auto again = clusterer.cluster(map, cells);
  ASSERT_EQ(again.size(), clusters.size());
  for (size_t i = 0; i < again.size(); ++i) EXPECT_EQ(again[i].id, clusters[i].id);
  map.writeCells([&](CellWriter& w) { w.set({7, 50, 0}, Cell{1, 3000}); });
  const auto changed = clusterer.cluster(map, findFrontierCells(map));
  ASSERT_EQ(changed.size(), 5u);
  for (int i = 0; i < 4; ++i) EXPECT_EQ(changed[i].id, clusters[i].id);
  EXPECT_EQ(changed[4].cells.size(), 7u);
  EXPECT_EQ(ids.count(changed[4].id), 0u);
}

// Brute-force gain: every ray sampled finely; the distinct unknown cells sampled before the
// first occupied one.
double bruteForceGain(const Map& map, const Eigen::Vector3d& origin, double yaw,
                      const GainSensor& s) {
  std::set<std::tuple<int, int, int>> seen;
  const Eigen::Matrix3d R = Eigen::AngleAxisd(yaw, Eigen::Vector3d::UnitZ()).toRotationMatrix();
  const double step = map.resolution() / 97.0;
  for (int r = 0; r < s.rows; ++r)
    for (int c = 0; c < s.columns; ++c) {
      const double u = ((c + 0.5) / s.columns - 0.5) * 2.0 * std::tan(0.5 * s.horizontal_fov_rad);
      const double v = ((r + 0.5) / s.rows - 0.5) * 2.0 * std::tan(0.5 * s.vertical_fov_rad);
      const Eigen::Vector3d d = R * Eigen::Vector3d(1.0, -u, -v).normalized();
      for (double t = 0.0; t <= s.max_range_m; t += step) {
        const VoxelKey k = map.keyOf(origin + t * d);
        const Cell* cell = map.findCell(k);
        if (cell && map.state(*cell) == CellState::kOccupied) break;
        if (cell && map.state(*cell) == CellState::kFree) continue;
        seen.insert({k.x, k.y, k.z});
      }
    }
  return double(seen.size());  // every unknown cell here is never observed: 1 bit each
}

TEST(Viewpoints, GainMatchesBruteForceRayCount) {
  MapParams p;
  p.resolution_m = 0.1;
  Map map(p);
  // A free room 2 x 2 x 1 m around the origin with an occupied wall at x = 0.6 m over half
  // its height; unknown beyond.
  map.writeCells([&](CellWriter& w) {
    for (int z = -5; z < 5; ++z)
      for (int y = -10; y < 10; ++y)
        for (int x = -10; x < 10; ++x)
          w.set({x, y, z}, (x == 6 && z < 0) ? Cell{1, 3000} : Cell{0, -2000});
  });
  GainSensor s;
  s.columns = 16;
  s.rows = 12;
  s.max_range_m = 2.5;
  const Eigen::Vector3d origin(0.03, -0.02, 0.04);
  for (double yaw : {0.0, 0.7, 2.5}) {
    const double expected = bruteForceGain(map, origin, yaw, s);
    const double gain = viewpointGainBits(map, map.blockView(), origin, yaw, s);
    ASSERT_GT(expected, 50.0);
    // Sampling can miss a cell a ray only clips at a corner, never add one.
    EXPECT_GE(gain, expected) << "yaw " << yaw;
    EXPECT_LE(gain, expected * 1.01 + 2.0) << "yaw " << yaw;
  }
  // Behind the wall there is less to see.
  EXPECT_LT(viewpointGainBits(map, map.blockView(), origin, 0.0, s),
            viewpointGainBits(map, map.blockView(), origin, 3.14159, s));
}

TEST(Viewpoints, GainInUnknownSpaceCountsEveryDistinctCell) {
  MapParams p;
  p.resolution_m = 0.1;
  const Map map(p);  // nothing observed: every cell is 1 bit
  GainSensor s;
  s.columns = 32;
  s.rows = 24;
  s.max_range_m = 8.0;
  const Eigen::Vector3d origin(0.01, 0.02, 0.03);
  const double expected = bruteForceGain(map, origin, 0.3, s);
  ASSERT_GT(expected, 40000.0) << "enough cells to grow the gain's cell set several times";
  const double gain = viewpointGainBits(map, map.blockView(), origin, 0.3, s);
  EXPECT_GE(gain, expected);
  EXPECT_LE(gain, expected * 1.01);
  // The same viewpoint again (the set is reused between viewpoints) and in a batch.
  EXPECT_EQ(viewpointGainBits(map, map.blockView(), origin, 0.3, s), gain);
  const auto batch = viewpointGainsBits(map, {origin, origin}, {0.3, 0.3}, s);
  EXPECT_EQ(batch, std::vector<double>({gain, gain}));
}

TEST(Viewpoints, RankedCandidatesInFreeSpace) {
  MapParams p;
  p.resolution_m = 0.1;
  Map map(p);
  // Free corridor x in [-3, 3] m, y in [-1, 1] m, z in [-0.5, 0.5] m; a frontier at both ends.
  map.writeCells([&](CellWriter& w) {
    for (int z = -5; z < 5; ++z)
      for (int y = -10; y < 10; ++y)
        for (int x = -30; x < 30; ++x) w.set({x, y, z}, Cell{0, -2000});
  });
  FrontierClusterer clusterer;
  FrontierFilter end;
  end.use_box = true;
  end.box_min_m = Eigen::Vector3d(2.85, -1.0, -0.5);
  end.box_max_m = Eigen::Vector3d(3.0, 1.0, 0.5);
  const auto clusters = clusterer.cluster(map, findFrontierCells(map, end));
  ASSERT_EQ(clusters.size(), 1u);
  ViewpointOptions o;
  o.radii_m = {1.0, 2.0};
  o.clearance_m = 0.2;
  o.top_k = 4;
  const auto views = clusterViewpoints(map, clusters[0], o);
  ASSERT_FALSE(views.empty());
  for (size_t i = 0; i < views.size(); ++i) {
    EXPECT_EQ(map.query(views[i].position_m), CellState::kFree);
    EXPECT_GT(views[i].gain_bits, 0.0);
    if (i) {
      EXPECT_GE(views[i - 1].score, views[i].score);
    }
    EXPECT_NEAR(
        views[i].gain_bits,
        viewpointGainBits(map, map.blockView(), views[i].position_m, views[i].yaw_rad, o.sensor),
        1e-9);
  }
  // Gain per metre from a robot position.
  o.robot_m = Eigen::Vector3d(0.0, 0.0, 0.0);
  const auto near = clusterViewpoints(map, clusters[0], o);
  ASSERT_FALSE(near.empty());
  EXPECT_NEAR(near.front().score, near.front().gain_bits / near.front().distance_m, 1e-9);
}

// Long queries stop on a deadline or a cancel flag (QueryStopped), leave no half-updated tracker
// behind, and a control that never fires changes nothing.
TEST(FrontierQueries, StopOnADeadlineOrACancelAndLeaveNoHalfSet) {
  Map map = randomMap(0.1, 8, 5);
  const std::vector<VoxelKey> expected = findFrontierCells(map);
  ASSERT_GT(expected.size(), 100u);
  std::atomic<bool> cancel{true};
  QueryControl cancelled;
  cancelled.cancel = &cancel;
  EXPECT_THROW(findFrontierCells(map, {}, 0, &cancelled), QueryStopped);
  const QueryControl late = QueryControl::within(-1.0);
  EXPECT_THROW(findFrontierCells(map, {}, 0, &late), QueryStopped);
  FrontierClusterer clusterer;
  EXPECT_THROW(clusterer.cluster(map, expected, &cancelled), QueryStopped);

  FrontierTracker tracker;
  EXPECT_TRUE(tracker.update(map).full);
  EXPECT_EQ(tracker.cells(), expected);
  map.clearBox(map.centerOf(map.bounds().min),
               map.centerOf(map.bounds().min) + Eigen::Vector3d::Constant(0.35));
  EXPECT_THROW(tracker.update(map, &late), QueryStopped);
  EXPECT_EQ(tracker.size(), 0u) << "a stopped update forgets the set";
  EXPECT_TRUE(tracker.update(map).full);
  EXPECT_EQ(tracker.cells(), findFrontierCells(map));

  cancel = false;  // the flag read when checked, not when the control was made
  const QueryControl hour = QueryControl::within(3600.0);
  QueryControl both = hour;
  both.cancel = &cancel;
  EXPECT_EQ(findFrontierCells(map, {}, 0, &both), tracker.cells());
  EXPECT_EQ(clusterer.cluster(map, tracker.cells(), &both).size(),
            FrontierClusterer().cluster(map, tracker.cells()).size());
}

// The coarse map against a brute force over the map's cells: a coarse cell is free when a child
// is free, unknown when every child is, occupied otherwise; at every allowed edge.
TEST(CoarseFrontiers, CoarseStatesMatchBruteForce) {
  const Map map = randomMap(0.1, 16, 9);
  const KeyBounds b = map.bounds();
  for (const int k : {1, 2, 4, 8}) {
    const Map coarse = coarseStateMap(map, k);
    EXPECT_DOUBLE_EQ(coarse.resolution(), 0.1 * k);
    const auto down = [k](int32_t v) { return static_cast<int32_t>(std::floor(double(v) / k)); };
    size_t counted[3] = {0, 0, 0};
    for (int32_t cz = down(b.min.z) - 1; cz <= down(b.max.z) + 1; ++cz)
      for (int32_t cy = down(b.min.y) - 1; cy <= down(b.max.y) + 1; ++cy)
        for (int32_t cx = down(b.min.x) - 1; cx <= down(b.max.x) + 1; ++cx) {
          bool any_free = false, any_occupied = false;
          for (int32_t z = cz * k; z < cz * k + k; ++z)
            for (int32_t y = cy * k; y < cy * k + k; ++y)
              for (int32_t x = cx * k; x < cx * k + k; ++x) {
                const Cell* c = map.findCell({x, y, z});
                const CellState s = c ? map.state(*c) : CellState::kUnknown;
                any_free |= s == CellState::kFree;
                any_occupied |= s == CellState::kOccupied;
              }
          const CellState want = any_free       ? CellState::kFree
                                 : any_occupied ? CellState::kOccupied
                                                : CellState::kUnknown;
          const Cell* got = coarse.findCell({cx, cy, cz});
          const CellState have = got ? coarse.state(*got) : CellState::kUnknown;
          ASSERT_EQ(have, want) << "k " << k << " at " << cx << " " << cy << " " << cz;
          ++counted[static_cast<int>(want == CellState::kFree) +
                    2 * static_cast<int>(want == CellState::kOccupied)];
        }
    EXPECT_GT(counted[1], 0u) << k;  // some free
    if (k == 1) {
      EXPECT_GT(counted[2], 0u);
    }
    EXPECT_GT(counted[0], 0u) << k;  // some unknown (the corner without blocks, the margin)
    // Its frontiers are those of a map like any other.
    EXPECT_EQ(findFrontierCells(coarse), bruteForceFrontiers(coarse)) << k;
  }
  // k = 1 keeps every state: the same frontier cells as the map.
  EXPECT_EQ(findFrontierCells(coarseStateMap(map, 1)), findFrontierCells(map));
  EXPECT_THROW((void)coarseStateMap(map, 3), InvalidArgument);
  EXPECT_THROW((void)coarseStateMap(map, 16), InvalidArgument);
  // The edge from a sensor's beam spacing: a 2-degree VLP-16 ring step at 20 m is 14 cells of
  // 5 cm (8 is the largest edge); a 0.2-degree step at 10 m is under one cell.
  EXPECT_EQ(coarseCellsForBeams(0.05, 2.0 * M_PI / 180.0, 20.0), 8);
  EXPECT_EQ(coarseCellsForBeams(0.05, 0.2 * M_PI / 180.0, 10.0), 1);
  EXPECT_EQ(coarseCellsForBeams(0.05, 0.6 * M_PI / 180.0, 20.0), 4);
  EXPECT_THROW((void)coarseCellsForBeams(0.05, NAN, 20.0), InvalidArgument);
}

TEST(FrontierArguments, RefusedCleanly) {
  const Map map = randomMap(0.1, 8, 3);
  FrontierFilter f;
  f.use_box = true;
  f.box_min_m = Eigen::Vector3d(NAN, 0, 0);
  EXPECT_THROW(findFrontierCells(map, f), InvalidArgument);
  f.box_min_m = Eigen::Vector3d(1, 0, 0);
  f.box_max_m = Eigen::Vector3d(0, 1, 1);
  EXPECT_THROW(findFrontierCells(map, f), InvalidArgument);
  FrontierFilter band;
  band.use_height = true;
  band.min_z_m = 1;
  band.max_z_m = 0;
  EXPECT_THROW(FrontierTracker{band}, InvalidArgument);
  FrontierFilter dist;
  dist.min_obstacle_distance_m = -1;
  EXPECT_THROW(findFrontierCells(map, dist), InvalidArgument);
  EXPECT_THROW(findFrontierCells(map, {}, -1), InvalidArgument);
  ClusterOptions c;
  c.min_cells = 0;
  EXPECT_THROW(FrontierClusterer{c}, InvalidArgument);
  FrontierCluster cluster;
  ViewpointOptions v;
  v.top_k = 0;
  EXPECT_THROW(clusterViewpoints(map, cluster, v), InvalidArgument);
  v.top_k = 1;
  v.sensor.max_range_m = NAN;
  EXPECT_THROW(clusterViewpoints(map, cluster, v), InvalidArgument);
  v.sensor.max_range_m = 5;
  v.radii_m = {0.0};
  EXPECT_THROW(clusterViewpoints(map, cluster, v), InvalidArgument);
  // Gains on CUDA need a map integrating on CUDA; auto on a CPU map walks the host blocks.
  const std::vector<Eigen::Vector3d> at = {Eigen::Vector3d(0.35, 0.35, 0.35)};
  EXPECT_THROW(viewpointGainsBits(map, at, {0.0}, GainSensor(), 0, Backend::kCuda),
               InvalidArgument);
  EXPECT_EQ(viewpointGainsBits(map, at, {0.0}, GainSensor(), 0, Backend::kAuto),
            viewpointGainsBits(map, at, {0.0}, GainSensor(), 0, Backend::kCpu));
  // The CUDA gain kernel's options: checked before any walk, on every backend.
  GainDeviceOptions bad;
  bad.refill_lanes = 0;
  EXPECT_THROW(viewpointGainsBits(map, at, {0.0}, GainSensor(), 0, Backend::kCpu, bad),
               InvalidArgument);
  bad.refill_lanes = 33;
  EXPECT_THROW(viewpointGainsBits(map, at, {0.0}, GainSensor(), 0, Backend::kAuto, bad),
               InvalidArgument);
  bad.refill_lanes = 32;
  bad.pool_blocks = (size_t(1) << 31) + 1;
  EXPECT_THROW(viewpointGainsBits(map, at, {0.0}, GainSensor(), 0, Backend::kCpu, bad),
               InvalidArgument);
  v.radii_m = {1.0};
  v.device_gains.refill_lanes = -1;
  EXPECT_THROW(clusterViewpoints(map, cluster, v), InvalidArgument);
}

TEST(Viewpoints, GainKernelNames) {
  for (const GainKernel k : kGainKernels) EXPECT_EQ(gainKernelFromName(gainKernelName(k)), k);
  EXPECT_STREQ(gainKernelName(GainKernel::kPooledQueued), "pooled-queued");
  EXPECT_TRUE(gainKernelPooled(GainKernel::kDeferred) && gainKernelQueued(GainKernel::kDeferred));
  EXPECT_TRUE(gainKernelPooled(GainKernel::kPooledDeferred) &&
              gainKernelDeferred(GainKernel::kPooledDeferred));
  EXPECT_FALSE(gainKernelQueued(GainKernel::kPooledDeferred) ||
               gainKernelDeferred(GainKernel::kPooled));
  EXPECT_STREQ(gainKernelName(GainKernel::kPooledDeferred), "pooled-deferred");
  EXPECT_FALSE(gainKernelPooled(GainKernel::kQueued) || gainKernelQueued(GainKernel::kPooled));
  EXPECT_FALSE(gainKernelPooled(GainKernel::kPlain) || gainKernelQueued(GainKernel::kPlain));
  EXPECT_EQ(gainKernelFromName("plain"), GainKernel::kPlain);
  EXPECT_THROW((void)gainKernelFromName("all"), InvalidArgument);
  EXPECT_THROW((void)gainKernelFromName(""), InvalidArgument);
  // The default is the plain kernel, the one checked longest against the CPU.
  EXPECT_EQ(GainDeviceOptions().kernel, GainKernel::kPlain);
  EXPECT_EQ(ViewpointOptions().device_gains.kernel, GainKernel::kPlain);
}

// The pooled gain kernels' directory (gain_walk.h's PoolDirectory, run on the device by
// poolBitmap and sized on the host by viewpointGainsOnDevice): over random boxes, negative
// keys and boxes at the key range's edge, every cell of the box finds an entry in
// [0, entries()), every entry is some block's and distinct blocks get distinct entries, and
// the blocks just outside the box get none.
TEST(GainPool, DirectoryIndexCoversTheBoxBlocksOnce) {
  std::mt19937 rng(34);
  std::uniform_int_distribution<int32_t> lo_of(-300, 300), dim_of(1, 40);
  std::vector<std::array<int32_t, 6>> boxes;
  for (int t = 0; t < 200; ++t)
    boxes.push_back({lo_of(rng), lo_of(rng), lo_of(rng), dim_of(rng), dim_of(rng), dim_of(rng)});
  const int32_t top = std::numeric_limits<int32_t>::max(),
                bottom = std::numeric_limits<int32_t>::min();
  boxes.push_back({top - 20, bottom, -8, 21, 17, 1});
  boxes.push_back({-1, -8, 7, 1, 1, 2});
  for (const auto& box : boxes) {
    const int32_t* lo = box.data();
    const int32_t* dims = box.data() + 3;
    const PoolDirectory dir = PoolDirectory::over(lo, dims);
    const uint64_t entries = dir.entries();
    ASSERT_GE(entries, 1u);
    std::map<int64_t, BlockKey> owner;
    for (int64_t z = lo[2]; z < int64_t(lo[2]) + dims[2]; ++z)
      for (int64_t y = lo[1]; y < int64_t(lo[1]) + dims[1]; ++y)
        for (int64_t x = lo[0]; x < int64_t(lo[0]) + dims[0]; ++x) {
          const BlockKey b = blockKeyOf(VoxelKey{int32_t(x), int32_t(y), int32_t(z)});
          const int64_t at = dir.indexOf(b);
          ASSERT_GE(at, 0) << "cell " << x << " " << y << " " << z;
          ASSERT_LT(uint64_t(at), entries);
          const auto [it, fresh] = owner.emplace(at, b);
          if (!fresh) {
            ASSERT_EQ(it->second, b) << "two blocks share entry " << at;
          }
        }
    EXPECT_EQ(owner.size(), entries) << "an entry no block of the box uses";
    // One block past each face (where that block key exists).
    const BlockKey first = blockKeyOf(VoxelKey{lo[0], lo[1], lo[2]});
    const int64_t f[3] = {first.x, first.y, first.z};
    for (int a = 0; a < 3; ++a)
      for (const int64_t k : {f[a] - 1, f[a] + dir.blocks[a]}) {
        if (k < (std::numeric_limits<int32_t>::min() >> kBlockBits) ||
            k > (std::numeric_limits<int32_t>::max() >> kBlockBits))
          continue;
        int32_t b[3] = {first.x, first.y, first.z};
        b[a] = static_cast<int32_t>(k);
        EXPECT_EQ(dir.indexOf(BlockKey{b[0], b[1], b[2]}), -1) << "axis " << a << " block " << k;
      }
  }
}

// The directory entries' protocol: a taken index reads back as its bitmap, a full pool as
// overflow, and the other states (empty, busy: issue 34's crash used busy as an index) name
// no bitmap; the largest pool's indices stay clear of the sentinels.
TEST(GainPool, EntriesNameTheirBitmapOnly) {
  for (const uint32_t pool : {1u, 64u, 1000u, uint32_t(kPoolMaxBlocks)}) {
    for (const uint32_t taken : {0u, pool / 2, pool - 1}) {
      const uint32_t e = poolEntryOf(taken, pool);
      EXPECT_NE(e, kPoolEmpty);
      EXPECT_NE(e, kPoolBusy);
      EXPECT_NE(e, kPoolOverflow);
      EXPECT_EQ(poolBitmapOf(e), int64_t(taken));
    }
    for (const uint32_t taken : {pool, pool + 1, 0xfffffffeu, 0xffffffffu})
      EXPECT_EQ(poolEntryOf(taken, pool), kPoolOverflow) << pool << " " << taken;
  }
  EXPECT_EQ(poolBitmapOf(kPoolEmpty), -1);
  EXPECT_EQ(poolBitmapOf(kPoolBusy), -1);
  EXPECT_EQ(poolBitmapOf(kPoolOverflow), -1);
  EXPECT_LT(kPoolMaxBlocks, uint64_t(kPoolOverflow));
}

}  // namespace
}  // namespace fragg::planning::test
