// MapOutputCache: after every edit (insertions, clear_bbx, erase by writeCells, truncate,
// merge, removal of a kept scan, load, reset) the incrementally kept occupied cloud and
// projected map equal a from-scratch build of the same map (occupiedCloud, projectedMap),
// with and without speckle hiding and a height band; insertions are incremental. Updates
// skipped (map_rate) lose nothing. Blocks are read from their state masks where no cell of
// theirs can widen the projected map, from their cells elsewhere. Paced (advance(), the server's
// paced_outputs): the changes listed at a publication are recomputed in shares over the next
// period's clouds; two periods after the last change, or at once with update(), the outputs
// equal a rebuild; the same read through a mask mirror. The messages a publisher sends, in roscpp's
// wire layout already (the cloud gathered in shares between publications), are byte for byte what
// roscpp makes of the cache's messages; a message roscpp holds is never written over.
#include "fragg_map/ros/output_cache.h"

#include <gtest/gtest.h>

#include <algorithm>
#include <array>
#include <cmath>
#include <cstdio>
#include <cstring>
#include <memory>
#include <random>
#include <string>
#include <vector>

#include "fragg_map/errors.h"
#include "fragg_map/ros/occupied_cloud.h"
#include "fragg_map/ros/projected_map.h"
#include "fragg_map/ros/wire_payload.h"
#include "map_fixtures.h"

namespace fragg::ros {
namespace {

using Triples = std::vector<std::array<float, 3>>;

Triples pointsOf(const sensor_msgs::PointCloud2& msg) {
  EXPECT_EQ(msg.point_step, 12u);
  EXPECT_EQ(msg.data.size(), size_t{msg.width} * 12);
  Triples out(msg.width);
  if (msg.width) std::memcpy(out.data(), msg.data.data(), msg.data.size());
  std::sort(out.begin(), out.end());
  return out;
}

/// The cache against a rebuild: same occupied centres, same grid (info and cells).
void expectSameAsRebuild(const fragg::Map& map, const MapOutputCache& cache,
                         const OutputCacheOptions& o, const std::string& step) {
  SCOPED_TRACE(step);
  const ::ros::Time stamp(7.0);
  const Triples got = pointsOf(cache.occupiedCloud("map", stamp));
  const Triples want = pointsOf(occupiedCloud(map, "map", stamp, o.hide_speckles,
                                              {o.occupancy_min_z_m, o.occupancy_max_z_m}));
  EXPECT_EQ(got.size(), want.size());
  EXPECT_TRUE(got == want);
  EXPECT_EQ(cache.occupiedCells(), want.size());
  const nav_msgs::OccupancyGrid g = cache.projectedMap("map", stamp);
  const nav_msgs::OccupancyGrid w = projectedMap(map, o.occupancy_min_z_m, o.occupancy_max_z_m,
                                                 "map", stamp, o.hide_speckles, o.octomap_bounds);
  EXPECT_EQ(g.info.width, w.info.width);
  EXPECT_EQ(g.info.height, w.info.height);
  EXPECT_DOUBLE_EQ(g.info.origin.position.x, w.info.origin.position.x);
  EXPECT_DOUBLE_EQ(g.info.origin.position.y, w.info.origin.position.y);
  EXPECT_FLOAT_EQ(g.info.resolution, w.info.resolution);
  EXPECT_EQ(g.header.frame_id, w.header.frame_id);
  ASSERT_EQ(g.data.size(), w.data.size());
  size_t differing = 0;
  for (size_t i = 0; i < g.data.size(); ++i) differing += g.data[i] != w.data[i];
  EXPECT_EQ(differing, 0u);
}

/// The messages a publisher sends (occupiedCloudWire, projectedMapWire: already in roscpp's
/// wire layout) are, byte for byte, what roscpp makes of occupiedCloud() and projectedMap().
/// Takes the cache's current messages (the next cloud message is gathered afresh).
void expectWireEqualsMessages(MapOutputCache* cache, const std::string& frame_id,
                              const std::string& step) {
  SCOPED_TRACE(step + ", wire");
  const ::ros::Time stamp(9, 87);
  const ::ros::SerializedMessage want_cloud =
      ::ros::serialization::serializeMessage(cache->occupiedCloud(frame_id, stamp));
  const ::ros::SerializedMessage want_grid =
      ::ros::serialization::serializeMessage(cache->projectedMap(frame_id, stamp));
  const PreserializedCloud cloud = cache->occupiedCloudWire(frame_id, stamp);
  const PreserializedGrid grid = cache->projectedMapWire(frame_id, stamp);
  // What roscpp sends: serializeMessage's bytes (for these types: the kept ones, no copy).
  const ::ros::SerializedMessage got_cloud = ::ros::serialization::serializeMessage(cloud);
  const ::ros::SerializedMessage got_grid = ::ros::serialization::serializeMessage(grid);
  EXPECT_EQ(got_cloud.buf.get(), cloud.wire.buf.get()) << "the cloud was copied";
  ASSERT_EQ(got_cloud.num_bytes, want_cloud.num_bytes);
  EXPECT_EQ(std::memcmp(got_cloud.buf.get(), want_cloud.buf.get(), want_cloud.num_bytes), 0);
  EXPECT_EQ(got_cloud.message_start, got_cloud.buf.get() + 4);
  ASSERT_EQ(got_grid.num_bytes, want_grid.num_bytes);
  EXPECT_EQ(std::memcmp(got_grid.buf.get(), want_grid.buf.get(), want_grid.num_bytes), 0);
  // And a subscriber reads the same message back.
  sensor_msgs::PointCloud2 read;
  ::ros::serialization::deserializeMessage(got_cloud, read);
  EXPECT_EQ(read.header.frame_id, frame_id);
  EXPECT_EQ(read.width, cache->occupiedCells());
  EXPECT_EQ(read.data.size(), size_t{read.width} * 12);
}

/// A scan of scattered points (isolated hits make speckles) and a wall, from `sensor`.
fragg::PointCloud scatteredScan(std::mt19937* rng, int points) {
  std::uniform_real_distribution<float> u(-2.5f, 2.5f);
  fragg::PointCloud cloud;
  for (int i = 0; i < points; ++i)
    cloud.points_S.emplace_back(2.0f + std::abs(u(*rng)), u(*rng), 0.4f * u(*rng));
  return cloud;
}

class OutputCacheSequence : public ::testing::TestWithParam<int> {};

TEST_P(OutputCacheSequence, EqualsARebuildAfterEveryEdit) {
  OutputCacheOptions o;
  if (GetParam() & 1) o.hide_speckles = true;
  if (GetParam() & 2) {
    o.occupancy_min_z_m = -0.3;
    o.occupancy_max_z_m = 0.45;
  }
  fragg::MapParams params = test::cpuParams(0.1);
  params.scans.keep = true;
  fragg::Map map(params);
  MapOutputCache cache(o);
  // 4: through a mask mirror (the server's way on a CUDA map).
  if (GetParam() & 4) cache.useMirror(std::make_shared<MaskMirror>());
  std::mt19937 rng(17 + GetParam());
  auto check = [&](const std::string& step, bool incremental) {
    const OutputCacheUpdate u = cache.update(map);
    if (incremental) {
      EXPECT_FALSE(u.full) << step;
    }
    expectSameAsRebuild(map, cache, o, step);
    expectWireEqualsMessages(&cache, "map", step);
  };
  check("empty map", false);
  std::vector<fragg::ScanId> ids;
  for (int i = 0; i < 6; ++i) {
    Eigen::Isometry3d T_map_sensor = Eigen::Isometry3d::Identity();
    T_map_sensor.translation() = Eigen::Vector3d(0.3 * i, 0.2 * i - 0.5, 0.1 * (i % 3));
    T_map_sensor.rotate(Eigen::AngleAxisd(0.4 * i, Eigen::Vector3d::UnitZ()));
    ids.push_back(map.insert(scatteredScan(&rng, 300), T_map_sensor,
                             fragg::SensorModel::autoFromCloud(0.0, -1.0))
                      .scan_id);
    check("insert " + std::to_string(i), true);
  }
  test::insertWall(map, Eigen::Vector3d(-1.0, 0.0, 0.0), 3.0);
  check("wall", true);
  // Several scans between two updates (a throttled publisher).
  test::insertWall(map, Eigen::Vector3d(0.0, 1.0, 0.2), 2.5);
  map.insert(scatteredScan(&rng, 200), Eigen::Isometry3d::Identity(),
             fragg::SensorModel::autoFromCloud(0.0, -1.0));
  check("two scans", true);
  map.remove(ids[2]);
  check("remove a kept scan", false);
  map.clearBox(Eigen::Vector3d(1.0, -1.0, -0.5), Eigen::Vector3d(2.2, 0.4, 0.3));
  check("clear_bbx", false);
  test::setCell(map, fragg::VoxelKey{60, 60, 0}, fragg::CellState::kOccupied);  // a far speckle
  test::setCell(map, fragg::VoxelKey{25, -3, 1}, fragg::CellState::kFree);
  check("written cells", true);
  fragg::Map cut = map.truncate(Eigen::Vector3d(-5.0, -5.0, -5.0), Eigen::Vector3d(0.5, 5.0, 5.0));
  check("truncate", false);
  map.merge(cut, fragg::MergeMode::kOverwrite);
  check("merge back", false);
  const std::string path = ::testing::TempDir() + "output_cache_test.fgm";
  map.save(path);
  fragg::Map other(test::cpuParams(0.1));
  test::insertWall(other, Eigen::Vector3d(0.0, 0.0, 0.0), 1.5);
  check("still the first map", true);
  map = fragg::Map::load(path, test::cpuParams(0.1));
  check("load", false);
  std::remove(path.c_str());
  map.insert(scatteredScan(&rng, 300), Eigen::Isometry3d::Identity(),
             fragg::SensorModel::autoFromCloud(0.0, -1.0));
  check("insert after load", true);
  map.reset();
  check("reset", false);
  test::insertWall(map, Eigen::Vector3d(0.5, 0.5, 0.0), 2.0);
  check("insert after reset", false);
}

INSTANTIATE_TEST_SUITE_P(Options, OutputCacheSequence, ::testing::Values(0, 1, 2, 3, 4, 5, 6, 7));

// The cloud is gathered from a list of the pieces holding cells into a message the cache
// keeps: pieces leave the list in every order (one leaving moves another into its place) and
// come back, and each call's header is its own.
TEST(OutputCache, PiecesThatLoseTheirCellsLeaveTheKeptCloud) {
  const OutputCacheOptions o;
  const std::vector<fragg::VoxelKey> keys = {{0, 0, 0}, {20, 0, 0}, {40, 0, 0}};  // 3 blocks
  std::vector<int> order = {0, 1, 2};
  do {
    const std::string trace = "freed in order " + std::to_string(order[0]) +
                              std::to_string(order[1]) + std::to_string(order[2]);
    SCOPED_TRACE(trace);
    fragg::Map map(test::cpuParams(0.1));
    MapOutputCache cache(o);
    auto step = [&](const std::string& name, size_t cells) {
      EXPECT_FALSE(cache.update(map).full) << name;
      expectSameAsRebuild(map, cache, o, name);
      const ::ros::Time stamp(3.0 + cells);
      const sensor_msgs::PointCloud2& msg = cache.occupiedCloud("odom", stamp);
      EXPECT_EQ(msg.header.frame_id, "odom") << name;
      EXPECT_EQ(msg.header.stamp, stamp) << name;
      EXPECT_EQ(msg.width, cells) << name;
      EXPECT_EQ(msg.data.size(), cells * 12) << name;
    };
    cache.update(map);  // the empty map: every later update is incremental
    for (const fragg::VoxelKey& k : keys) test::setCell(map, k, fragg::CellState::kOccupied);
    step("three blocks", 3);
    for (size_t j = 0; j < keys.size(); ++j) {
      test::setCell(map, keys[order[j]], fragg::CellState::kFree);
      step("freed " + std::to_string(j + 1), keys.size() - j - 1);
    }
    test::setCell(map, keys[order[0]], fragg::CellState::kOccupied);
    step("one back", 1);
    test::insertWall(map, Eigen::Vector3d(0.0, 0.0, 0.0), 2.0);  // outgrows the kept buffer
    EXPECT_FALSE(cache.update(map).full);
    expectSameAsRebuild(map, cache, o, "wall");
    EXPECT_GT(cache.occupiedCells(), 100u);
  } while (std::next_permutation(order.begin(), order.end()));
}

TEST(OutputCache, OnlyChangedBlocksAreRead) {
  fragg::Map map(test::cpuParams(0.1));
  MapOutputCache cache;
  test::insertWall(map, Eigen::Vector3d(0.0, 0.0, 0.0), 2.0);
  EXPECT_TRUE(cache.update(map).full);
  EXPECT_EQ(cache.update(map).blocks_read, 0u);  // nothing changed
  // The same wall again: free cells get freer and hit cells more occupied, no cell changes
  // state, so no block is read though many changed.
  const uint64_t before_again = map.revision();
  test::insertWall(map, Eigen::Vector3d(0.0, 0.0, 0.0), 2.0);
  EXPECT_GT(map.changedBlocksSince(before_again, fragg::BlockChange::kAny).size(), 0u);
  const OutputCacheUpdate again = cache.update(map);
  EXPECT_FALSE(again.full);
  EXPECT_EQ(again.blocks_read, 0u);
  expectSameAsRebuild(map, cache, OutputCacheOptions(), "the same wall again");
  test::setCell(map, fragg::VoxelKey{100, 100, 0}, fragg::CellState::kOccupied);
  const OutputCacheUpdate u = cache.update(map);
  EXPECT_FALSE(u.full);
  EXPECT_EQ(u.blocks_read, 1u);
  expectSameAsRebuild(map, cache, OutputCacheOptions(), "one cell");
}

// map_rate: the server skips the cache's update after the clouds that are not due. Skipping
// loses nothing: one update after many edits (cells that changed and changed back in
// between, blocks new since the last update) equals a rebuild, incrementally, as does a
// cache updated after every edit.
class OutputCacheSkipping : public ::testing::TestWithParam<int> {};

TEST_P(OutputCacheSkipping, OneUpdateAfterManyEditsEqualsARebuild) {
  OutputCacheOptions o;
  o.hide_speckles = GetParam() & 1;
  const int every = GetParam() & 2 ? 7 : 3;  // edits between two updates of `skipping`
  fragg::Map map(test::cpuParams(0.1));
  MapOutputCache skipping(o), each(o);
  std::mt19937 rng(5 + GetParam());
  skipping.update(map);
  // Cells away from the scans (which reach ~5 m): only the writes below change them.
  const fragg::VoxelKey seen{100, -2, 0}, flicker{-80, 60, 1}, back{-81, 60, 1};
  test::setCell(map, seen, fragg::CellState::kOccupied);
  int skipped_updates = 0;
  for (int edit = 1; edit <= 4 * every; ++edit) {
    Eigen::Isometry3d T_map_sensor = Eigen::Isometry3d::Identity();
    T_map_sensor.translation() = Eigen::Vector3d(0.25 * edit, 0.1 * (edit % 4), 0.0);
    T_map_sensor.rotate(Eigen::AngleAxisd(0.3 * edit, Eigen::Vector3d::UnitZ()));
    map.insert(scatteredScan(&rng, 200), T_map_sensor,
               fragg::SensorModel::autoFromCloud(0.0, -1.0));
    // Between two updates: a cell the last update saw occupied goes free and comes back; a
    // cell in a block new since the last update turns occupied, then free; another turns
    // occupied and stays.
    if (edit % every == 1) {
      test::setCell(map, seen, fragg::CellState::kFree);
      test::setCell(map, flicker, fragg::CellState::kOccupied);
    }
    if (edit % every == 2) {
      test::setCell(map, seen, fragg::CellState::kOccupied);
      test::setCell(map, flicker, fragg::CellState::kFree);
      test::setCell(map, back, fragg::CellState::kOccupied);
    }
    each.update(map);
    expectSameAsRebuild(map, each, o, "every edit, edit " + std::to_string(edit));
    if (edit % every != 0) {
      ++skipped_updates;
      continue;
    }
    const uint64_t last_seen = skipping.revision();
    const OutputCacheUpdate u = skipping.update(map);
    EXPECT_FALSE(u.full) << edit;
    EXPECT_EQ(skipping.revision(), map.revision());
    EXPECT_GT(map.revision(), last_seen);
    EXPECT_GT(u.blocks_read, 0u);
    expectSameAsRebuild(map, skipping, o, "after skipping, edit " + std::to_string(edit));
    EXPECT_EQ(skipping.occupiedCells(), each.occupiedCells());
    test::setCell(map, back, fragg::CellState::kFree);  // for the next window
  }
  EXPECT_EQ(skipped_updates, 4 * (every - 1));
}

INSTANTIATE_TEST_SUITE_P(Options, OutputCacheSkipping, ::testing::Values(0, 1, 2, 3));

/// Writes `log_odds_fx` (observed) into cell `v`.
void setLogOdds(fragg::Map& map, const fragg::VoxelKey& v, int16_t log_odds_fx) {
  fragg::Cell c;
  c.log_odds_fx = log_odds_fx;
  map.writeCells([&](fragg::CellWriter& cells) { cells.set(v, c); });
}

// The masks miss observed cells in the unknown band, which still widen the projected map's
// bounds: a block that could widen them is read from its cells, the others from their masks.
TEST(OutputCache, CellsInTheUnknownBandAtTheEdgeWidenTheGrid) {
  fragg::Map map(test::cpuParams(0.1));
  MapOutputCache cache;
  test::insertWall(map, Eigen::Vector3d(0.0, 0.0, 0.0), 2.0);
  EXPECT_TRUE(cache.update(map).full);
  const fragg::VoxelKey edge{90, -70, 0};  // far outside the wall's bounds
  // Occupied, then back in the band before the next update: the block is listed (its masks
  // changed twice) but its masks show nothing.
  test::setCell(map, edge, fragg::CellState::kOccupied);
  setLogOdds(map, edge, 0);
  ASSERT_EQ(map.state(*map.findCell(edge)), fragg::CellState::kUnknown);
  OutputCacheUpdate u = cache.update(map);
  EXPECT_FALSE(u.full);
  EXPECT_EQ(u.blocks_read, 1u);
  EXPECT_EQ(u.blocks_cells_read, 1u);
  expectSameAsRebuild(map, cache, OutputCacheOptions(), "a band cell at the edge");
  // The same inside the bounds: its masks suffice.
  const fragg::VoxelKey inside{40, -30, 0};
  test::setCell(map, inside, fragg::CellState::kFree);
  setLogOdds(map, inside, 0);
  u = cache.update(map);
  EXPECT_EQ(u.blocks_read, 1u);
  EXPECT_EQ(u.blocks_cells_read, 0u);
  expectSameAsRebuild(map, cache, OutputCacheOptions(), "a band cell inside");
  // Outside the bounds, but the masks show free cells at the block's edges on every side: no
  // cell of it can lie further out, its masks suffice (a band cell inside it included).
  const fragg::VoxelKey corner{-104, 96, 0};  // the block's low x, low y corner
  ASSERT_EQ(corner.x % 8, 0);
  ASSERT_EQ(corner.y % 8, 0);
  for (const fragg::VoxelKey& v : {corner, fragg::VoxelKey{corner.x + 7, corner.y + 7, 0}})
    test::setCell(map, v, fragg::CellState::kFree);
  const fragg::VoxelKey band{corner.x + 3, corner.y + 4, 0};
  test::setCell(map, band, fragg::CellState::kOccupied);
  setLogOdds(map, band, 0);
  u = cache.update(map);
  EXPECT_EQ(u.blocks_read, 1u);
  EXPECT_EQ(u.blocks_cells_read, 0u);
  expectSameAsRebuild(map, cache, OutputCacheOptions(), "masks at the block's edges");
  // The wall seen from elsewhere: most of its blocks lie inside the bounds.
  test::insertWall(map, Eigen::Vector3d(0.4, 0.3, 0.0), 2.0);
  u = cache.update(map);
  EXPECT_GT(u.blocks_read, 0u);
  EXPECT_LT(u.blocks_cells_read, u.blocks_read);
  expectSameAsRebuild(map, cache, OutputCacheOptions(), "the wall again");
}

// Many random changes between updates (cells turning occupied, free or back into the unknown
// band anywhere around the map, scans), with and without speckles hidden: the incrementally
// kept cloud and grid equal a rebuild after every update.
class OutputCacheRandom : public ::testing::TestWithParam<int> {};

TEST_P(OutputCacheRandom, EqualsARebuildAfterManyRandomChanges) {
  OutputCacheOptions o;
  o.hide_speckles = GetParam() & 1;
  o.octomap_bounds = GetParam() & 2;
  fragg::Map map(test::cpuParams(0.1));
  MapOutputCache cache(o);
  std::mt19937 rng(101 + GetParam());
  test::insertWall(map, Eigen::Vector3d(0.0, 0.0, 0.0), 2.0);
  EXPECT_TRUE(cache.update(map).full);
  std::uniform_int_distribution<int> xy(-60, 60), z(-4, 4), pick(0, 3);
  const fragg::OccupancyModel& model = map.model();
  const int16_t values[] = {model.max_fx, model.min_fx, 0, static_cast<int16_t>(model.max_fx / 2)};
  size_t cells_read = 0, blocks_read = 0;
  for (int round = 0; round < 20; ++round) {
    for (int w = 0; w < 25; ++w) {
      const fragg::VoxelKey v{xy(rng), xy(rng), z(rng)};
      const fragg::Cell* c = map.findCell(v);
      // A cell seen for the first time leaves the unknown band (as an insertion's first
      // update does: the change log lists its block); an observed cell may go back into it.
      const bool seen = c && map.state(*c) != fragg::CellState::kUnknown;
      const int16_t value = values[seen ? pick(rng) : pick(rng) % 2];
      setLogOdds(map, v, value);
    }
    if (round % 4 == 0) {
      Eigen::Isometry3d T_map_sensor = Eigen::Isometry3d::Identity();
      T_map_sensor.translation() = Eigen::Vector3d(0.2 * round - 3.0, 0.1 * (round % 5), 0.0);
      T_map_sensor.rotate(Eigen::AngleAxisd(0.5 * round, Eigen::Vector3d::UnitZ()));
      map.insert(scatteredScan(&rng, 150), T_map_sensor,
                 fragg::SensorModel::autoFromCloud(0.0, -1.0));
    }
    const OutputCacheUpdate u = cache.update(map);
    EXPECT_FALSE(u.full) << round;
    blocks_read += u.blocks_read;
    cells_read += u.blocks_cells_read;
    expectSameAsRebuild(map, cache, o, "round " + std::to_string(round));
  }
  // Both ways of reading a block were taken.
  EXPECT_GT(cells_read, 0u);
  EXPECT_LT(cells_read, blocks_read);
}

INSTANTIATE_TEST_SUITE_P(Options, OutputCacheRandom, ::testing::Values(0, 1, 2, 3));

/// A LiDAR-like ring: `points` returns at 1.5-9 m around the sensor, on a ground plane 1.2 m
/// below it and on a wall of scattered posts.
fragg::PointCloud ringScan(std::mt19937* rng, int points) {
  std::uniform_real_distribution<float> angle(0.0f, 6.2832f), range(1.5f, 9.0f), h(-1.2f, 1.5f);
  fragg::PointCloud cloud;
  for (int i = 0; i < points; ++i) {
    const float a = angle(*rng), r = range(*rng);
    const bool ground = i % 3 != 0;
    cloud.points_S.emplace_back(r * std::cos(a), r * std::sin(a), ground ? -1.2f : h(*rng));
  }
  return cloud;
}

// Thousands of blocks a step (the pieces recomputed in parallel, the flat piece and column
// tables growing as the sensor moves on), a height band, octomap bounds or not, several scans
// between two updates: the kept cloud and grid equal a rebuild after every update.
class OutputCacheManyBlocks : public ::testing::TestWithParam<int> {};

TEST_P(OutputCacheManyBlocks, EqualsARebuildAsTheSensorMovesOn) {
  OutputCacheOptions o;
  o.occupancy_min_z_m = -1.0;
  o.occupancy_max_z_m = 0.8;
  o.octomap_bounds = GetParam() & 1;
  fragg::Map map(test::cpuParams(0.05));
  MapOutputCache cache(o);
  std::mt19937 rng(29 + GetParam());
  EXPECT_TRUE(cache.update(map).full);
  size_t most_read = 0;
  for (int step = 0; step < 5; ++step) {
    for (int scan = 0; scan < 2; ++scan) {
      Eigen::Isometry3d T_map_sensor = Eigen::Isometry3d::Identity();
      T_map_sensor.translation() = Eigen::Vector3d(2.5 * step + 0.7 * scan, 0.3 * scan, 0.0);
      T_map_sensor.rotate(Eigen::AngleAxisd(0.2 * step, Eigen::Vector3d::UnitZ()));
      map.insert(ringScan(&rng, 4000), T_map_sensor, fragg::SensorModel::autoFromCloud(0.0, 12.0));
    }
    const OutputCacheUpdate u = cache.update(map);
    EXPECT_FALSE(u.full) << step;
    most_read = std::max(most_read, u.blocks_read);
    expectSameAsRebuild(map, cache, o, "step " + std::to_string(step));
  }
  EXPECT_GT(most_read, 1024u);  // the parallel recompute ran
}

INSTANTIATE_TEST_SUITE_P(Options, OutputCacheManyBlocks, ::testing::Values(0, 1));

// Clouds every 1/8 s, the whole-map outputs at 1 Hz, paced: the changes listed at a publication
// (with_grid) are recomputed in shares over the next period's clouds (not all at once); two
// periods after the last change the queue is empty and the outputs equal a rebuild; update()
// catches up at once.
class OutputCachePaced : public ::testing::TestWithParam<int> {};

TEST_P(OutputCachePaced, EqualsARebuildTwoPeriodsAfterTheLastChange) {
  OutputCacheOptions o;
  o.hide_speckles = GetParam() & 1;
  o.octomap_bounds = GetParam() & 2;
  o.occupancy_min_z_m = -1.0;
  o.occupancy_max_z_m = 0.8;
  fragg::Map map(test::cpuParams(0.05));
  MapOutputCache paced(o), caught_up(o);
  // 4: both through one mask mirror (shared, as the server's outputs share it); 8: as the
  // server that brings it up to date between clouds, each paced call reads it one cloud behind
  // (MaskMirror::acceptLag) and a sync follows the call.
  // 16 (with 8 and 4): as the server with shares_between_clouds, a cloud's call only at a
  // publication, and each cloud's share of the queue between clouds, after the sync.
  const auto mirror = std::make_shared<MaskMirror>();
  const bool follows = GetParam() & 8;
  const bool between = GetParam() & 16;
  if (GetParam() & 4) {
    paced.useMirror(mirror);
    caught_up.useMirror(mirror);
  }
  size_t lagged = 0;  // publications that read the mirror one cloud behind
  std::mt19937 rng(57 + GetParam());
  constexpr double kPeriodS = 1.0, kIntervalS = 0.125;  // exact in binary
  EXPECT_TRUE(paced.advance(map, 0.0, kPeriodS, true).full);
  EXPECT_TRUE(caught_up.update(map).full);
  double now_s = kIntervalS, published_s = 0.0;
  // As the server: a publication (the grid drawn, the changes listed, the messages sent) once a
  // period; the cloud message is gathered in shares once a period's queue is recomputed.
  size_t gather_shares = 0;  // clouds between publications that gathered part of the cloud
  size_t queued_after = 0;   // the queue right after the call whose result advance returns
  const auto advance = [&](double t_s) {
    const bool due = t_s - published_s >= kPeriodS;
    if (due) published_s = t_s;
    if (follows) mirror->acceptLag(1);
    OutputCacheUpdate u;
    if (!between || due) {
      u = paced.advance(map, t_s, kPeriodS, due);
      queued_after = paced.queuedBlocks();
    }
    if (follows) {
      lagged += due && mirror->revision() + 1 == map.revision();
      mirror->acceptLag(0);
      (void)mirror->sync(map);  // between clouds
    }
    if (between) {
      // The share between clouds (right after a publication's call too: a share of nothing).
      const OutputCacheUpdate share = paced.advance(map, t_s, kPeriodS, false);
      EXPECT_FALSE(share.full);
      if (!due) {
        u = share;
        queued_after = paced.queuedBlocks();
      }
    }
    if (due) {
      expectWireEqualsMessages(&paced, "map", "publication at " + std::to_string(t_s) + " s");
    } else if (u.pieces_gathered > 0) {
      ++gather_shares;
      EXPECT_EQ(u.blocks_queued, 0u) << "gathered while pieces were still to be recomputed";
    }
    return u;
  };
  size_t shares = 0;  // clouds that recomputed some blocks and left others queued
  for (int cloud = 0; cloud < 12; ++cloud, now_s += kIntervalS) {
    Eigen::Isometry3d T_map_sensor = Eigen::Isometry3d::Identity();
    T_map_sensor.translation() = Eigen::Vector3d(0.6 * cloud, 0.1 * (cloud % 3), 0.0);
    T_map_sensor.rotate(Eigen::AngleAxisd(0.15 * cloud, Eigen::Vector3d::UnitZ()));
    map.insert(ringScan(&rng, 2000), T_map_sensor, fragg::SensorModel::autoFromCloud(0.0, 10.0));
    const OutputCacheUpdate u = advance(now_s);
    EXPECT_FALSE(u.full) << cloud;
    EXPECT_EQ(u.blocks_queued, queued_after);
    shares += u.blocks_read > 0 && u.blocks_queued > 0;
    if (cloud == 5) {
      // update() lists and takes everything at once: a second cache kept that way agrees.
      (void)caught_up.update(map);
      expectSameAsRebuild(map, caught_up, o, "update() at cloud 5");
      EXPECT_EQ(caught_up.queuedBlocks(), 0u);
    }
  }
  EXPECT_GE(shares, 2u) << "the listed blocks were not spread over the clouds";
  // No more changes: two periods after the last one everything is in.
  const double last_change_s = now_s - kIntervalS;
  for (; now_s <= last_change_s + 2 * kPeriodS; now_s += kIntervalS) (void)advance(now_s);
  // (Counted to here: through a mirror with speckles hidden, the first period's shares draw from
  // the first cloud's masks, where every hit is a speckle: nothing to gather yet.)
  EXPECT_GE(gather_shares, 2u) << "the cloud message was not gathered between publications";
  EXPECT_EQ(paced.queuedBlocks(), 0u);
  (void)paced.advance(map, now_s, kPeriodS, true);  // a publication: the grid drawn
  EXPECT_EQ(paced.queuedBlocks(), 0u);
  expectSameAsRebuild(map, paced, o, "two periods after the last cloud");
  // Blocks queued, then update(): everything at once.
  published_s = now_s - kPeriodS;  // the next call is a publication: it lists the new changes
  for (int cloud = 0; cloud < 3; ++cloud, now_s += kIntervalS) {
    Eigen::Isometry3d T_map_sensor = Eigen::Isometry3d::Identity();
    T_map_sensor.translation() = Eigen::Vector3d(-0.8 * cloud, 1.0, 0.0);
    map.insert(ringScan(&rng, 2000), T_map_sensor, fragg::SensorModel::autoFromCloud(0.0, 10.0));
    (void)advance(now_s);
  }
  // (Following, the publication read the mirror one cloud behind: nothing new listed yet.)
  if (!follows) {
    EXPECT_GT(paced.queuedBlocks(), 0u);
  }
  EXPECT_EQ(paced.update(map).blocks_queued, 0u);
  expectSameAsRebuild(map, paced, o, "update() after paced clouds");
  if (follows) {
    EXPECT_GE(lagged, 2u) << "no publication read a lagging mirror: not tested";
  }
}

INSTANTIATE_TEST_SUITE_P(Options, OutputCachePaced, ::testing::Values(0, 3, 4, 7, 12, 15, 28, 31));

// A message handed to roscpp is never written again while roscpp holds it (a latched topic, a
// subscriber's queue): the next one goes into another buffer; one roscpp let go of is reused.
// A frame_id too long for the room kept in front of the payload still gives the right message.
TEST(OutputCache, WireMessagesRoscppHoldsAreNotOverwritten) {
  fragg::Map map(test::cpuParams(0.1));
  MapOutputCache cache;
  test::insertWall(map, Eigen::Vector3d::Zero(), 3.0);
  (void)cache.update(map);
  const sensor_msgs::PointCloud2 first = cache.occupiedCloud("map", ::ros::Time(1.0));
  PreserializedCloud held = cache.occupiedCloudWire("map", ::ros::Time(1.0));
  const std::vector<uint8_t> held_bytes(held.wire.buf.get(),
                                        held.wire.buf.get() + held.wire.num_bytes);
  // More cells, two more messages while the first is held.
  for (int i = 0; i < 2; ++i) {
    test::insertWall(map, Eigen::Vector3d(0.0, 1.0 + i, 0.2), 2.5);
    (void)cache.update(map);
    const PreserializedCloud next = cache.occupiedCloudWire("map", ::ros::Time(2.0 + i));
    EXPECT_NE(next.wire.buf.get(), held.wire.buf.get());
  }
  EXPECT_TRUE(std::equal(held_bytes.begin(), held_bytes.end(), held.wire.buf.get()))
      << "a held message was written over";
  sensor_msgs::PointCloud2 read;
  ::ros::serialization::deserializeMessage(held.wire, read);
  EXPECT_EQ(read.data, first.data);
  // One held, the next let go of at once: that one's buffer serves the one after.
  held = cache.occupiedCloudWire("map", ::ros::Time(5.0));
  const uint8_t* let_go = cache.occupiedCloudWire("map", ::ros::Time(6.0)).wire.buf.get();
  EXPECT_NE(let_go, held.wire.buf.get());
  EXPECT_EQ(cache.occupiedCloudWire("map", ::ros::Time(7.0)).wire.buf.get(), let_go)
      << "a buffer nobody holds was not reused";
  expectWireEqualsMessages(&cache, std::string(3000, 'f'), "a long frame_id");
  expectWireEqualsMessages(&cache, "map", "after the long frame_id");
}

TEST(OutputCache, RefreshingOnOccupiedChangesOnlyIsRefused) {
  OutputCacheOptions o;
  o.refresh_on = fragg::BlockChange::kOccupied;  // would miss cells that became free
  EXPECT_THROW(MapOutputCache cache(o), fragg::InvalidArgument);
  o.refresh_on = fragg::BlockChange::kAny;
  EXPECT_NO_THROW(MapOutputCache cache(o));
}

TEST(OutputCache, BadHeightsAreRefused) {
  OutputCacheOptions o;
  o.occupancy_min_z_m = 1.0;
  o.occupancy_max_z_m = 0.0;
  EXPECT_THROW(MapOutputCache{o}, fragg::InvalidArgument);
  o.occupancy_min_z_m = std::nan("");
  EXPECT_THROW(MapOutputCache{o}, fragg::InvalidArgument);
}

}  // namespace
}  // namespace fragg::ros
