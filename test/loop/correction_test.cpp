// Map::remove and Map::correctPoses: exact where no clamping happens, close to a rebuild
// where it does, and bad arguments leave the map alone.
#include <gtest/gtest.h>

#include <cmath>
#include <cstdio>
#include <filesystem>
#include <limits>
#include <map>
#include <string>
#include <vector>

#include "fragg_map/errors.h"
#include "fragg_map/io/dataset.h"
#include "fragg_map/io/point_file.h"
#include "fragg_map/io/pose_file.h"
#include "loop_scenes.h"

namespace fragg {
namespace {

const std::string kData = FRAGG_REAL_DATA;

MapParams keeping(double res = 0.05) {
  MapParams p;
  p.resolution_m = res;
  p.backend = Backend::kCpu;
  p.scans.keep = true;
  return p;
}

PointCloud room() { return test::roomScan(4.0, 1.0, 2.0, 16, 360); }

TEST(RemoveTest, RemovingEveryScanReturnsEveryCellToUnknown) {
  // Four scans cannot reach a clamping bound with OctoMap's default model (4 hits: 3,468 <
  // 3,476; 4 misses: -1,660 > -2,036), so removal is exact here.
  Map map(keeping());
  for (int i = 0; i < 4; ++i) map.insert(room(), test::poseAt(i), test::lidar());
  ASSERT_GT(map.knownVoxelCount(), 100000u);
  for (ScanId id : {2u, 0u, 3u, 1u}) map.remove(id);
  EXPECT_EQ(map.knownVoxelCount(), 0u);
  EXPECT_EQ(map.scanCount(), 0u);
  EXPECT_EQ(map.scanStore().size(), 0u);
}

TEST(RemoveTest, RemovingAScanEqualsNeverInsertingIt) {
  Map all(keeping()), without(keeping());
  for (int i = 0; i < 3; ++i) all.insert(room(), test::poseAt(i), test::lidar());
  for (int i : {0, 2}) without.insert(room(), test::poseAt(i), test::lidar());
  all.remove(1);
  std::string why;
  EXPECT_TRUE(test::sameCells(all, without, &why)) << why;
  EXPECT_THROW(all.remove(1), InvalidArgument);  // already gone
}

SensorModel noisyLidar() {
  SensorModel m = test::lidar();
  m.range_noise_m = 0.03;
  m.range_noise_quadratic_per_m = 0.002;
  return m;
}

TEST(RemoveTest, WithRangeNoiseRemovalStillEqualsNeverInserting) {
  // The clearing margin comes from each kept scan's own sensor model, also after a save and
  // load, so removal walks exactly the cells the insertion updated.
  Map all(keeping()), without(keeping()), plain(keeping());
  for (int i = 0; i < 3; ++i) {
    all.insert(room(), test::poseAt(i), noisyLidar());
    plain.insert(room(), test::poseAt(i), test::lidar());
  }
  for (int i : {0, 2}) without.insert(room(), test::poseAt(i), noisyLidar());
  EXPECT_FALSE(test::sameCells(all, plain));  // the margin changed the map
  const std::string path = std::string(FRAGG_TEST_TMP) + "/noisy_kept.fgm";
  all.save(path);
  Map loaded = Map::load(path, Backend::kCpu);
  EXPECT_EQ(loaded.scanStore().record(1).model.range_noise_m, 0.03);
  EXPECT_EQ(loaded.scanStore().record(1).model.range_noise_quadratic_per_m, 0.002);
  all.remove(1);
  loaded.remove(1);
  std::string why;
  EXPECT_TRUE(test::sameCells(all, without, &why)) << why;
  EXPECT_TRUE(test::sameCells(loaded, without, &why)) << why;
  for (ScanId id : {0u, 2u}) all.remove(id);
  EXPECT_EQ(all.knownVoxelCount(), 0u);
}

TEST(CorrectTest, CorrectingEveryScanEqualsARebuildWhenNothingClamps) {
  Map drifted(keeping()), rebuilt(keeping());
  std::map<ScanId, Eigen::Isometry3d> corrected;
  for (int i = 0; i < 4; ++i) {
    drifted.insert(room(), test::poseAt(i, 0.04 * i, 0.01 * i), test::lidar());
    rebuilt.insert(room(), test::poseAt(i), test::lidar());
    corrected[ScanId(i)] = test::poseAt(i);
  }
  EXPECT_LT(test::sameState(drifted, rebuilt), 0.99);  // the drift matters
  const CorrectionStats st = drifted.correctPoses(corrected);
  EXPECT_EQ(st.scans, 4u);
  EXPECT_GT(st.removal.cells_updated, 0u);
  std::string why;
  EXPECT_TRUE(test::sameCells(drifted, rebuilt, &why)) << why;
  for (ScanId id = 0; id < 4; ++id)
    EXPECT_TRUE(drifted.scanStore().record(id).T_map_sensor.isApprox(corrected[id]));
}

TEST(CorrectTest, WithClampingTheCorrectedMapStaysCloseToARebuild) {
  // Twelve scans, the last six drifting away; correcting those six is compared with a map
  // built from scratch with the corrected poses.
  Map drifted(keeping()), rebuilt(keeping());
  std::map<ScanId, Eigen::Isometry3d> corrected;
  for (int i = 0; i < 12; ++i) {
    const double drift = i < 6 ? 0.0 : 0.03 * (i - 5);
    drifted.insert(room(), test::poseAt(i % 6, drift, 0.5 * drift), test::lidar());
    rebuilt.insert(room(), test::poseAt(i % 6), test::lidar());
    if (i >= 6) corrected[ScanId(i)] = test::poseAt(i % 6);
  }
  const double before = test::sameState(drifted, rebuilt);
  drifted.correctPoses(corrected);
  const double after = test::sameState(drifted, rebuilt);
  std::printf("[loop] room, 12 scans, 6 corrected: same state before %.4f %%, after %.4f %%\n",
              100 * before, 100 * after);
  EXPECT_GT(after, before);
  EXPECT_GE(after, 0.995);
}

TEST(CorrectTest, BadArgumentsLeaveTheMapUntouched) {
  Map map(keeping()), twin(keeping());
  for (int i = 0; i < 3; ++i) {
    map.insert(room(), test::poseAt(i), test::lidar());
    twin.insert(room(), test::poseAt(i), test::lidar());
  }
  const uint64_t revision = map.revision();
  Eigen::Isometry3d nan_pose = test::poseAt(1);
  nan_pose.translation().x() = std::numeric_limits<double>::quiet_NaN();
  Eigen::Isometry3d sheared = test::poseAt(1);
  sheared.linear()(0, 1) += 0.3;
  // The bad entry comes after a good one: nothing may have been removed when it is found.
  EXPECT_THROW(map.correctPoses({{0, test::poseAt(0, 0.1)}, {7, test::poseAt(1)}}),
               InvalidArgument);
  EXPECT_THROW(map.correctPoses({{0, test::poseAt(0, 0.1)}, {1, nan_pose}}), InvalidArgument);
  EXPECT_THROW(map.correctPoses({{0, test::poseAt(0, 0.1)}, {2, sheared}}), InvalidArgument);
  EXPECT_THROW(map.remove(99), InvalidArgument);
  EXPECT_EQ(map.revision(), revision);
  std::string why;
  EXPECT_TRUE(test::sameCells(map, twin, &why)) << why;

  MapParams plain = keeping();
  plain.scans.keep = false;
  Map no_scans(plain);
  no_scans.insert(room(), test::poseAt(0), test::lidar());
  EXPECT_THROW(no_scans.remove(0), InvalidArgument);
  EXPECT_THROW(no_scans.correctPoses({{0, test::poseAt(0)}}), InvalidArgument);
}

TEST(CorrectTest, ScansReachingIntoAClearedBoxCanNoLongerBeRemoved) {
  // Far apart scans (10 m range): clearing a box around the first only touches the first.
  Map map(keeping());
  Eigen::Isometry3d far = test::poseAt(0);
  far.translation().x() += 100.0;
  map.insert(room(), test::poseAt(0), test::lidar());
  map.insert(room(), far, test::lidar());
  map.clearBox(Eigen::Vector3d(-1, -1, -1), Eigen::Vector3d(1, 1, 1));
  EXPECT_FALSE(map.scanStore().canRemove(0));
  EXPECT_TRUE(map.scanStore().canRemove(1));
  const uint64_t revision = map.revision();
  EXPECT_THROW(map.correctPoses({{0, test::poseAt(0, 0.1)}}), InvalidArgument);
  EXPECT_THROW(map.remove(0), InvalidArgument);
  EXPECT_EQ(map.revision(), revision);
  // The flag is kept in the file; the other scan still moves.
  const std::string path = std::string(FRAGG_TEST_TMP) + "/cleared.fgm";
  map.save(path);
  Map loaded = Map::load(path, Backend::kCpu);
  EXPECT_FALSE(loaded.scanStore().canRemove(0));
  Eigen::Isometry3d moved = far;
  moved.translation().y() += 0.2;
  EXPECT_EQ(loaded.correctPoses({{1, moved}}).scans, 1u);
  // A direct edit of the map makes every kept scan unremovable.
  loaded.writeCells([](CellWriter&) {});
  EXPECT_FALSE(loaded.scanStore().canRemove(1));
}

TEST(CorrectTest, CorrectionWorksAfterSavingAndLoading) {
  Map live(keeping());
  for (int i = 0; i < 5; ++i) live.insert(room(), test::poseAt(i, 0.02 * i), test::lidar());
  const std::string path = std::string(FRAGG_TEST_TMP) + "/before_correction.fgm";
  live.save(path);
  Map loaded = Map::load(path, Backend::kCpu);
  const std::map<ScanId, Eigen::Isometry3d> fix{{3, test::poseAt(3)}, {4, test::poseAt(4)}};
  live.correctPoses(fix);
  loaded.correctPoses(fix);
  std::string why;
  EXPECT_TRUE(test::sameCells(live, loaded, &why)) << why;
}

/// Real scans: the pose of some scans is disturbed as drift would, then corrected back; the
/// result is compared with the map built with the right poses from the start.
void expectCorrectionOnReal(const std::vector<Scan>& scans, const std::vector<int>& disturbed,
                            double res, double max_range_m, const char* label) {
  Map map(keeping(res)), truth(keeping(res));
  const SensorModel sensor = SensorModel::autoFromCloud(0.0, max_range_m);
  std::map<ScanId, Eigen::Isometry3d> fix;
  Eigen::Isometry3d error = Eigen::Isometry3d::Identity();
  error.translation() = Eigen::Vector3d(0.15, -0.1, 0.02);
  error.linear() = Eigen::AngleAxisd(0.03, Eigen::Vector3d::UnitZ()).toRotationMatrix();
  for (size_t i = 0; i < scans.size(); ++i) {
    const bool bad = std::find(disturbed.begin(), disturbed.end(), int(i)) != disturbed.end();
    const auto st = map.insert(scans[i].cloud,
                               bad ? error * scans[i].T_map_sensor : scans[i].T_map_sensor, sensor);
    truth.insert(scans[i].cloud, scans[i].T_map_sensor, sensor);
    if (bad) fix[st.scan_id] = scans[i].T_map_sensor;
  }
  const double before = test::sameState(map, truth);
  map.correctPoses(fix);
  const MapComparison c = compareMaps(map, truth);
  std::printf(
      "[loop] %s: %zu scans, %zu corrected: same state before %.4f %%, after %.4f %% of "
      "%llu cells known in either\n",
      label, scans.size(), fix.size(), 100 * before, 100 * c.agreementInEither(),
      static_cast<unsigned long long>(c.known_in_either));
  EXPECT_GT(c.known_in_either, 10000u);
  EXPECT_GE(c.agreementInEither(), 0.995) << label;
}

Scan scanOf(const std::string& path, const Eigen::Isometry3d& T = Eigen::Isometry3d::Identity()) {
  Scan s;
  s.cloud = readPointFile(path);
  s.T_map_sensor = T;
  return s;
}

TEST(CorrectRealTest, VelodynePair) {
  const std::string dir = kData + "/small_gicp_pair/";
  // Missing real data fails, as in the other real-data tests (never a silent skip).
  ASSERT_TRUE(std::filesystem::exists(dir)) << "no real data at " << dir;
  const Eigen::Isometry3d T = readMatrix4(dir + "T_target_source.txt");
  expectCorrectionOnReal({scanOf(dir + "target.ply"), scanOf(dir + "source.ply", T)}, {1}, 0.05,
                         30.0, "small_gicp_pair (Velodyne)");
}

TEST(CorrectRealTest, RgbdFrames) {
  const std::string dir = kData + "/slambook2_ch5_rgbd";
  // Missing real data fails, as in the other real-data tests (never a silent skip).
  ASSERT_TRUE(std::filesystem::exists(dir)) << "no real data at " << dir;
  auto source = openDataset(dir);
  std::vector<Scan> scans;
  Scan s;
  while (source->next(s)) scans.push_back(s);
  ASSERT_EQ(scans.size(), 5u);
  expectCorrectionOnReal(scans, {3, 4}, 0.03, -1.0, "slambook2 RGB-D (5 frames)");
}

}  // namespace
}  // namespace fragg
