// OctoMap's update semantics through Map::insert.
#include <gtest/gtest.h>

#include <cstring>
#include <limits>
#include <unordered_set>

#include "fragg_map/errors.h"
#include "fragg_map/map.h"
#include "test_scenes.h"

namespace fragg {
namespace {

using test::cloudOf;
using test::sensorAtVoxelCentre;

const Cell* cellAt(const Map& m, int x, int y, int z) { return m.findCell(VoxelKey{x, y, z}); }

TEST(InsertTest, EndpointHitAndFreeCellsBefore) {
  Map map;
  const InsertStats s =
      map.insert(cloudOf({{1.0f, 0.f, 0.f}}), sensorAtVoxelCentre(), SensorModel::autoFromCloud());
  EXPECT_EQ(s.rays_hit, 1u);
  for (int x = 0; x < 20; ++x) {
    const Cell* c = cellAt(map, x, 0, 0);
    ASSERT_NE(c, nullptr) << x;
    EXPECT_EQ(map.state(*c), CellState::kFree) << x;
    EXPECT_EQ(c->log_odds_fx, map.model().miss_fx);
    EXPECT_EQ(c->hits, 0);
  }
  const Cell* end = cellAt(map, 20, 0, 0);
  ASSERT_NE(end, nullptr);
  EXPECT_EQ(map.state(*end), CellState::kOccupied);
  EXPECT_EQ(end->hits, 1);
  EXPECT_EQ(map.knownVoxelCount(), 21u);
  EXPECT_EQ(map.query({1.03, 0.03, 0.03}), CellState::kOccupied);
  EXPECT_EQ(map.query({-1.0, 0.0, 0.0}), CellState::kUnknown);
}

TEST(InsertTest, EachCellUpdatedOncePerScan) {
  Map map;
  map.insert(cloudOf({{1.0f, 0.f, 0.f}, {1.01f, 0.001f, 0.f}, {0.5f, 0.f, 0.f}}),
             sensorAtVoxelCentre(), SensorModel::autoFromCloud());
  // Cell 5 lies on every ray but is updated once; cell 10 is a hit (0.5 m) and stays a hit.
  EXPECT_EQ(cellAt(map, 5, 0, 0)->log_odds_fx, map.model().miss_fx);
  EXPECT_EQ(cellAt(map, 20, 0, 0)->log_odds_fx, map.model().hit_fx);
  EXPECT_EQ(cellAt(map, 20, 0, 0)->hits, 1);
}

TEST(InsertTest, HitWinsOverFree) {
  Map map;
  // The second ray passes through the first one's endpoint cell (10, 0, 0).
  map.insert(cloudOf({{0.5f, 0.f, 0.f}, {1.0f, 0.f, 0.f}}), sensorAtVoxelCentre(),
             SensorModel::autoFromCloud());
  const Cell* c = cellAt(map, 10, 0, 0);
  EXPECT_EQ(c->log_odds_fx, map.model().hit_fx);
  EXPECT_EQ(map.state(*c), CellState::kOccupied);
  EXPECT_EQ(map.state(*cellAt(map, 15, 0, 0)), CellState::kFree);
}

TEST(InsertTest, BeyondMaxRangeClearsUpToMaxRangeOnly) {
  Map map;
  const InsertStats s = map.insert(cloudOf({{10.f, 0.f, 0.f}}), sensorAtVoxelCentre(),
                                   SensorModel::autoFromCloud(0.0, 2.0));
  EXPECT_EQ(s.rays_free_only, 1u);
  EXPECT_EQ(s.rays_hit, 0u);
  for (int x = 0; x < 40; ++x) EXPECT_EQ(map.state(*cellAt(map, x, 0, 0)), CellState::kFree);
  const Cell* end = cellAt(map, 40, 0, 0);
  EXPECT_TRUE(end == nullptr || !end->observed());
  EXPECT_EQ(map.query({5.0, 0.0, 0.0}), CellState::kUnknown);
  EXPECT_EQ(map.query({10.0, 0.0, 0.0}), CellState::kUnknown);
}

TEST(InsertTest, BelowMinRangeAndInvalidPointsAreDropped) {
  Map map;
  const float nan = std::numeric_limits<float>::quiet_NaN();
  const float inf = std::numeric_limits<float>::infinity();
  const InsertStats s =
      map.insert(cloudOf({{0.1f, 0.f, 0.f}, {nan, 0.f, 0.f}, {inf, 1.f, 1.f}, {0.f, 0.f, 0.f}}),
                 sensorAtVoxelCentre(), SensorModel::autoFromCloud(0.5, 10.0));
  EXPECT_EQ(s.dropped_min_range, 1u);
  EXPECT_EQ(s.dropped_invalid, 3u);
  EXPECT_EQ(map.knownVoxelCount(), 0u);
}

TEST(InsertTest, BadInputThrowsAndLeavesTheMapAlone) {
  Map map;
  map.insert(cloudOf({{1.0f, 0.f, 0.f}}), sensorAtVoxelCentre(), SensorModel::autoFromCloud());
  const size_t known = map.knownVoxelCount();
  Eigen::Isometry3d bad = sensorAtVoxelCentre();
  bad.translation().x() = std::numeric_limits<double>::quiet_NaN();
  EXPECT_THROW(map.insert(cloudOf({{2.f, 0.f, 0.f}}), bad, SensorModel::autoFromCloud()),
               InvalidArgument);
  Eigen::Isometry3d scaled = sensorAtVoxelCentre();
  scaled.linear() *= 2.0;
  EXPECT_THROW(map.insert(cloudOf({{2.f, 0.f, 0.f}}), scaled, SensorModel::autoFromCloud()),
               InvalidArgument);
  EXPECT_THROW(map.insert(PointCloud(), sensorAtVoxelCentre(), SensorModel::autoFromCloud()),
               InvalidArgument);
  EXPECT_THROW(map.insert(cloudOf({{2.f, 0.f, 0.f}}), sensorAtVoxelCentre(),
                          SensorModel::pinhole(0.0, 1.0, 0.0, 5.0)),
               InvalidArgument);
  EXPECT_EQ(map.knownVoxelCount(), known);
  EXPECT_EQ(map.scanCount(), 1u);
}

TEST(InsertTest, ExplicitSensorCountsPointsOutsideItsFrustum) {
  Map map;
  // A camera looking along +z with a 60 x 40 degree view: the point along +x is outside.
  const SensorModel cam = SensorModel::pinhole(60 * M_PI / 180, 40 * M_PI / 180, 0.0, 10.0);
  const InsertStats s = map.insert(cloudOf({{0.f, 0.f, 2.f}, {2.f, 0.f, 0.f}, {0.5f, 0.3f, 2.f}}),
                                   sensorAtVoxelCentre(), cam);
  EXPECT_EQ(s.dropped_outside_frustum, 1u);
  EXPECT_EQ(s.rays_hit, 2u);
  EXPECT_EQ(map.query({0.025, 0.025, 2.025}), CellState::kOccupied);
  EXPECT_EQ(map.query({2.025, 0.025, 0.025}), CellState::kUnknown);
}

TEST(InsertTest, NoReturnRaysClearOnlyWhenEnabled) {
  const float nan = std::numeric_limits<float>::quiet_NaN();
  PointCloud organised = cloudOf({{2.f, -0.2f, 0.f}, {nan, nan, nan}, {2.f, 0.2f, 0.f}});
  organised.width = 3;
  organised.height = 1;
  PointCloud two_rows = organised;
  two_rows.points_S.insert(two_rows.points_S.end(), organised.points_S.begin(),
                           organised.points_S.end());
  two_rows.height = 2;
  for (bool enabled : {false, true}) {
    MapParams p;
    p.clear_no_return_rays = enabled;
    Map map(p);
    const InsertStats s =
        map.insert(two_rows, sensorAtVoxelCentre(), SensorModel::autoFromCloud(0.0, 4.0));
    // The middle ray points along +x: (3, 0, 0) lies past both returns.
    EXPECT_EQ(s.rays_no_return, enabled ? 2u : 0u);
    EXPECT_EQ(map.query({3.0, 0.01, 0.01}), enabled ? CellState::kFree : CellState::kUnknown);
  }
}

TEST(InsertTest, ThreadCountDoesNotChangeTheMap) {
  const PointCloud scan = test::roomScan(6.0, 1.5, 2.5, 32, 720);
  Eigen::Isometry3d T = Eigen::Isometry3d::Identity();
  T.translation() = Eigen::Vector3d(0.31, -0.17, 1.2);
  MapParams one, two;
  one.threads = 1;
  two.threads = 2;
  Map a(one), b(two);
  for (int i = 0; i < 3; ++i) {
    T.translation().x() += 0.37;
    a.insert(scan, T, SensorModel::autoFromCloud());
    b.insert(scan, T, SensorModel::autoFromCloud());
  }
  ASSERT_EQ(a.blockCount(), b.blockCount());
  a.forEachBlock([&](const BlockKey& k, const Block& block) {
    const Block* other = b.findBlock(k);
    ASSERT_NE(other, nullptr);
    EXPECT_EQ(std::memcmp(&block, other, sizeof(Block)), 0);
  });
}

TEST(InsertTest, ClearBoxMakesCellsUnknown) {
  Map map;
  map.insert(cloudOf({{1.0f, 0.f, 0.f}}), sensorAtVoxelCentre(), SensorModel::autoFromCloud());
  map.clearBox({0.5, -0.1, -0.1}, {2.0, 0.1, 0.1});
  EXPECT_EQ(map.query({1.03, 0.03, 0.03}), CellState::kUnknown);
  EXPECT_EQ(map.query({0.7, 0.03, 0.03}), CellState::kUnknown);
  EXPECT_EQ(map.query({0.3, 0.03, 0.03}), CellState::kFree);
  EXPECT_THROW(map.clearBox({1, 1, 1}, {0, 0, 0}), InvalidArgument);
}

TEST(InsertTest, OccupiedAtMovesOnlyWhenACellCrossesTheOccupiedThreshold) {
  MapParams p;
  p.backend = Backend::kCpu;
  Map map(p);
  const PointCloud wall = cloudOf({{1.0f, 0.f, 0.f}, {1.0f, 0.2f, 0.f}, {1.0f, -0.2f, 0.f}});
  map.insert(wall, test::sensorAtVoxelCentre(), SensorModel::autoFromCloud());
  const uint64_t first = map.revision();
  size_t with_hits = 0;
  const std::vector<BlockKey> occupied_changed = map.changedBlocksSince(0, BlockChange::kOccupied);
  const std::unordered_set<BlockKey, BlockKeyHash> listed(occupied_changed.begin(),
                                                          occupied_changed.end());
  EXPECT_EQ(listed.size(), occupied_changed.size());
  map.forEachBlock([&](const BlockKey& key, const Block& block) {
    bool occupied = false;
    for (const Cell& c : block.cells) occupied |= map.state(c) == CellState::kOccupied;
    EXPECT_EQ(map.blockView().stamps(key).occupied_at, occupied ? first : 0u);
    // Every block of the first scan got observed cells: their states changed.
    EXPECT_EQ(map.blockView().stamps(key).state_at, first);
    EXPECT_EQ(listed.count(key), occupied ? 1u : 0u);
    with_hits += occupied;
  });
  EXPECT_GE(with_hits, 1u);
  // The same scan again: log-odds move (changed_at), no cell crosses the threshold.
  map.insert(wall, test::sensorAtVoxelCentre(), SensorModel::autoFromCloud());
  size_t changed = 0;
  map.forEachBlock([&](const BlockKey& key, const Block&) {
    changed += map.blockView().stamps(key).changed_at > first;
    EXPECT_LE(map.blockView().stamps(key).occupied_at, first);
    // Free cells got freer and occupied ones more occupied: no state changed.
    EXPECT_LE(map.blockView().stamps(key).state_at, first);
  });
  EXPECT_GT(changed, 0u);
  EXPECT_EQ(map.changedBlocksSince(first, BlockChange::kAny).size(), changed);
  EXPECT_TRUE(map.changedBlocksSince(first, BlockChange::kState).empty());
  EXPECT_EQ(map.changedBlocksSince(0, BlockChange::kState).size(), map.blockCount());
  EXPECT_TRUE(map.changedBlocksSince(first, BlockChange::kOccupied).empty());
  // changedRefsSince lists the same blocks as changedSince, each with its own cells.
  const BlockView view = map.blockView();
  for (const BlockChange what : {BlockChange::kAny, BlockChange::kOccupied, BlockChange::kState}) {
    for (const uint64_t since : {uint64_t{0}, first}) {
      const std::vector<BlockKey> keys = view.changedSince(since, what);
      const std::vector<BlockRef> refs = view.changedRefsSince(since, what);
      ASSERT_EQ(refs.size(), keys.size());
      for (size_t i = 0; i < refs.size(); ++i) {
        EXPECT_EQ(refs[i].key, keys[i]);
        EXPECT_EQ(refs[i].block, view.findBlock(keys[i]));
      }
    }
  }
}

TEST(InsertTest, RangeNoiseKeepsAHitsOwnSurfaceFromBeingCleared) {
  // Scan 1 hits cell 20 (x in [1.00, 1.05) m); scan 2 hits 1.5 cm behind it, in cell 21.
  // OctoMap's rule clears cell 20 with scan 2's ray; with 2 cm of range noise the ray stops
  // updating free space 2 cm before its hit, so cell 20 keeps scan 1's hit alone.
  auto run = [](const SensorModel& model) {
    Map map;
    map.insert(cloudOf({{1.0f, 0.f, 0.f}}), sensorAtVoxelCentre(), model);
    map.insert(cloudOf({{1.04f, 0.f, 0.f}}), sensorAtVoxelCentre(), model);
    return map;
  };
  const SensorModel plain = SensorModel::autoFromCloud();
  SensorModel noisy = plain;
  noisy.range_noise_m = 0.02;
  SensorModel quadratic = plain;  // sigma(1.04 m) = 0.02 * 1.04^2 = 2.2 cm
  quadratic.range_noise_quadratic_per_m = 0.02;
  const Map a = run(plain), b = run(noisy), c = run(quadratic);
  const int16_t hit = a.model().hit_fx, miss = a.model().miss_fx;
  EXPECT_EQ(cellAt(a, 20, 0, 0)->log_odds_fx, hit + miss);
  EXPECT_EQ(cellAt(b, 20, 0, 0)->log_odds_fx, hit);
  EXPECT_EQ(cellAt(c, 20, 0, 0)->log_odds_fx, hit);
  for (const Map* m : {&a, &b, &c}) {
    EXPECT_EQ(cellAt(*m, 21, 0, 0)->log_odds_fx, hit);
    EXPECT_EQ(cellAt(*m, 19, 0, 0)->log_odds_fx, 2 * miss);  // left 6.5 cm before the hit
    EXPECT_EQ(m->state(*cellAt(*m, 20, 0, 0)), CellState::kOccupied);
  }
  // Rays clipped at max range say nothing about a surface: they clear up to the max range.
  Map clipped;
  SensorModel noisy_clipped = noisy;
  noisy_clipped.max_range_m = 1.0;
  clipped.insert(cloudOf({{3.0f, 0.f, 0.f}}), sensorAtVoxelCentre(), noisy_clipped);
  EXPECT_EQ(cellAt(clipped, 19, 0, 0)->log_odds_fx, miss);
  // A bad noise figure is an error that leaves the map alone.
  for (double bad : {-0.01, std::numeric_limits<double>::quiet_NaN(), 11.0}) {
    SensorModel m = plain;
    m.range_noise_m = bad;
    Map map;
    EXPECT_THROW(map.insert(cloudOf({{1.0f, 0.f, 0.f}}), sensorAtVoxelCentre(), m),
                 InvalidArgument);
    EXPECT_EQ(map.knownVoxelCount(), 0u);
    m = plain;
    m.range_noise_quadratic_per_m = bad;
    EXPECT_THROW(map.insert(cloudOf({{1.0f, 0.f, 0.f}}), sensorAtVoxelCentre(), m),
                 InvalidArgument);
  }
  EXPECT_NE(noisy.describe().find("noise=0.02"), std::string::npos) << noisy.describe();
}

TEST(MapParamsTest, CudaHostThreadsBelowZeroAreRefused) {
  MapParams p;
  p.backend = Backend::kCpu;  // validated whichever backend runs
  p.cuda.host_threads = -1;
  EXPECT_THROW(Map{p}, InvalidArgument);
  p.cuda.host_threads = 0;  // every core
  EXPECT_NO_THROW(Map{p});
}

TEST(MapParamsTest, CudaRayPieceStepsOutsideTheRangeAreRefused) {
  MapParams p;
  p.backend = Backend::kCpu;
  for (int bad : {-1, 4097}) {
    p.cuda.ray_piece_steps = bad;
    EXPECT_THROW(Map{p}, InvalidArgument) << bad;
  }
  for (int good : {0, 1, 32, 4096}) {
    p.cuda.ray_piece_steps = good;
    EXPECT_NO_THROW(Map{p}) << good;
  }
}

}  // namespace
}  // namespace fragg
