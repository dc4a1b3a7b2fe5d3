// Map::insertSequence: a batch of scans gives the map, statistics and kept scans that one
// insert() call per scan gives (on the CPU backend here; the gpu suite checks the CUDA
// backend's staging against the CPU), and checks every scan's arguments before the first.
#include <gtest/gtest.h>

#include <cmath>
#include <map>
#include <string>
#include <vector>

#include "fragg_map/errors.h"
#include "fragg_map/map.h"
#include "same_map.h"
#include "test_scenes.h"

namespace fragg {
namespace {

using test::expectSameMap;

MapParams cpuParams() {
  MapParams p;
  p.resolution_m = 0.05;
  p.backend = Backend::kCpu;
  p.scans.keep = true;
  return p;
}

Eigen::Isometry3d poseAt(int i) {
  Eigen::Isometry3d T = Eigen::Isometry3d::Identity();
  T.translation() = Eigen::Vector3d(0.11 * i - 0.3, 0.07 * (i % 3), 1.1 + 0.01 * i);
  T.rotate(Eigen::AngleAxisd(0.13 * i, Eigen::Vector3d::UnitZ()));
  return T;
}

/// Ten scans of two rooms: the same cloud object several times in a row, auto and explicit
/// models mixed, stamps and frame ids.
struct Batch {
  PointCloud small = test::roomScan(2.5, 1.1, 1.4, 24, 240);
  PointCloud large = test::roomScan(4.0, 1.3, 1.6, 32, 360);
  std::vector<ScanToInsert> scans;

  Batch() {
    for (int i = 0; i < 10; ++i) {
      ScanToInsert s;
      s.cloud = i % 4 < 2 ? &small : &large;
      s.T_map_sensor = poseAt(i);
      s.sensor = i % 3 == 2 ? SensorModel::spinningLidar(-0.9, 0.6, 0.2, 6.0)
                            : SensorModel::autoFromCloud(0.0, 5.0);
      s.stamp_ns = 1000 + i;
      s.sensor_frame = i % 2 ? "velodyne" : "lidar_front";
      scans.push_back(s);
    }
  }
};

std::vector<InsertStats> insertOneByOne(Map& m, const std::vector<ScanToInsert>& scans) {
  std::vector<InsertStats> out;
  for (const ScanToInsert& s : scans)
    out.push_back(m.insert(*s.cloud, s.T_map_sensor, s.sensor, s.stamp_ns, s.sensor_frame));
  return out;
}

void expectSameStats(const std::vector<InsertStats>& a, const std::vector<InsertStats>& b) {
  ASSERT_EQ(a.size(), b.size());
  for (size_t i = 0; i < a.size(); ++i) {
    EXPECT_EQ(a[i].scan_id, b[i].scan_id) << i;
    EXPECT_EQ(a[i].points_in, b[i].points_in) << i;
    EXPECT_EQ(a[i].voxel_visits, b[i].voxel_visits) << i;
    EXPECT_EQ(a[i].cells_updated, b[i].cells_updated) << i;
    EXPECT_EQ(a[i].blocks_created, b[i].blocks_created) << i;
    EXPECT_EQ(a[i].sensor.type, b[i].sensor.type) << i;
    EXPECT_EQ(a[i].sensor.max_range_m, b[i].sensor.max_range_m) << i;
  }
}

TEST(InsertSequenceTest, SameMapStatsAndKeptScansAsOneInsertAtATime) {
  const Batch batch;
  Map one(cpuParams()), seq(cpuParams());
  const std::vector<InsertStats> a = insertOneByOne(one, batch.scans);
  const std::vector<InsertStats> b = seq.insertSequence(batch.scans);
  expectSameStats(a, b);
  expectSameMap(one, seq, "ten scans");
  EXPECT_GT(seq.knownVoxelCount(), 10000u);
  ASSERT_EQ(seq.scanStore().size(), batch.scans.size());
  for (ScanId id = 0; id < batch.scans.size(); ++id) {
    const ScanRecord& r = seq.scanStore().record(id);
    EXPECT_EQ(r.stamp_ns, batch.scans[id].stamp_ns);
    EXPECT_EQ(r.sensor_frame, batch.scans[id].sensor_frame);
    EXPECT_TRUE(r.T_map_sensor.isApprox(batch.scans[id].T_map_sensor));
    EXPECT_EQ(r.explicit_model, one.scanStore().record(id).explicit_model);
  }
  // The kept scans are the same: a correction moves both maps alike.
  std::map<ScanId, Eigen::Isometry3d> moved{{2, poseAt(20)}, {7, poseAt(21)}};
  one.correctPoses(moved);
  seq.correctPoses(moved);
  expectSameMap(one, seq, "after correcting two scans");
  // A later batch continues the scan indices.
  const std::vector<InsertStats> more = seq.insertSequence({batch.scans[0], batch.scans[5]});
  ASSERT_EQ(more.size(), 2u);
  EXPECT_EQ(more[0].scan_id, 10u);
  EXPECT_EQ(more[1].scan_id, 11u);
}

TEST(InsertSequenceTest, EveryScanIsCheckedBeforeTheFirstIsInserted) {
  Batch batch;
  Map m(cpuParams());
  std::vector<ScanToInsert> bad = batch.scans;
  bad[6].T_map_sensor.matrix()(0, 3) = std::nan("");
  try {
    m.insertSequence(bad);
    FAIL() << "a non-finite pose in scan 6 was accepted";
  } catch (const InvalidArgument& e) {
    EXPECT_NE(std::string(e.what()).find("scan 6 of the sequence"), std::string::npos) << e.what();
  }
  bad = batch.scans;
  bad[3].cloud = nullptr;
  EXPECT_THROW(m.insertSequence(bad), InvalidArgument);
  bad = batch.scans;
  bad[9].sensor_frame.assign(kMaxSensorFrameChars + 1, 'x');
  EXPECT_THROW(m.insertSequence(bad), InvalidArgument);
  const PointCloud empty;
  bad = batch.scans;
  bad[1].cloud = &empty;
  EXPECT_THROW(m.insertSequence(bad), InvalidArgument);
  EXPECT_EQ(m.blockCount(), 0u);
  EXPECT_EQ(m.scanStore().size(), 0u);
  EXPECT_TRUE(m.insertSequence({}).empty());
  EXPECT_EQ(m.insertSequence(batch.scans).back().scan_id, 9u);  // nothing was used up before
}

TEST(InsertSequenceTest, HeightBandAndQuantisedKeptPointsAsOneInsertAtATime) {
  const Batch batch;
  MapParams band = cpuParams();
  band.height_filter.min_z_m = 0.3;
  band.height_filter.max_z_m = 2.2;
  MapParams quantised = cpuParams();
  quantised.scans.point_step_m = 0.004;
  for (const MapParams& p : {band, quantised}) {
    Map one(p), seq(p);
    expectSameStats(insertOneByOne(one, batch.scans), seq.insertSequence(batch.scans));
    expectSameMap(one, seq, p.height_filter.active() ? "height band" : "quantised points");
  }
}

}  // namespace
}  // namespace fragg
