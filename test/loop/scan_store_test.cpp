// The scan store: float32 (default) and quantised points, memory budget, spill files, and the
// kept scans in .fgm.
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <cstring>
#include <filesystem>
#include <fstream>
#include <limits>
#include <string>

#include "fragg_map/errors.h"
#include "fragg_map/internal/scan_codec.h"
#include "fragg_map/map.h"
#include "fragg_map/map_file_format.h"
#include "loop_scenes.h"

namespace fragg {
namespace {

TEST(ScanStoreTest, QuantisedPointsStayWithinHalfAStepAndKeepNoReturns) {
  PointCloud c = test::roomScan(4.0, 1.0, 2.0, 8, 90);
  c.points_S[5] = Eigen::Vector3f::Constant(std::numeric_limits<float>::quiet_NaN());
  c.points_S[6] = Eigen::Vector3f(std::numeric_limits<float>::infinity(), 0.f, 0.f);
  const EncodedPoints e = encodePoints(c, 0.001);
  EXPECT_DOUBLE_EQ(e.step_m, 0.001);  // 4 m fit 16 bits at 1 mm
  EXPECT_EQ(e.data.size(), c.size() * 6);
  const PointCloud d = decodePoints(e);
  ASSERT_EQ(d.size(), c.size());
  EXPECT_EQ(d.width, c.width);
  EXPECT_EQ(d.height, c.height);
  for (size_t i = 0; i < c.size(); ++i) {
    if (i == 5 || i == 6) {
      EXPECT_FALSE(d.points_S[i].allFinite());
      continue;
    }
    EXPECT_LE((d.points_S[i] - c.points_S[i]).cwiseAbs().maxCoeff(), 0.0005f + 1e-6f) << i;
  }
  // Encoding the decoded cloud again gives the same bytes: re-insertion repeats the rays.
  EXPECT_EQ(encodePoints(d, 0.001).data, e.data);
  // The decoded cloud from the encoding pass is the same as decoding afterwards.
  PointCloud same_pass;
  encodePoints(c, 0.001, &same_pass);
  ASSERT_EQ(same_pass.size(), d.size());
  for (size_t i = 0; i < d.size(); ++i)
    if (d.points_S[i].allFinite()) {
      EXPECT_EQ(same_pass.points_S[i], d.points_S[i]) << i;
    } else {
      EXPECT_FALSE(same_pass.points_S[i].allFinite()) << i;
    }
  // Large clouds take the parallel path: same bytes as a point-by-point encoding.
  PointCloud big = test::roomScan(4.0, 1.0, 2.0, 64, 1024);
  PointCloud big_decoded;
  const EncodedPoints eb = encodePoints(big, 0.001, &big_decoded);
  EXPECT_EQ(decodePoints(eb).points_S, big_decoded.points_S);
  for (size_t i = 0; i < big.size(); i += 997) {
    PointCloud one;
    one.points_S = {big.points_S[i]};
    const EncodedPoints e1 = encodePoints(one, eb.step_m);
    EXPECT_EQ(0, std::memcmp(e1.data.data(), eb.data.data() + 6 * i, 6)) << i;
  }
}

TEST(ScanStoreTest, FarPointsWidenTheStepAndFloatModeIsExact) {
  PointCloud c;
  c.points_S = {{60.f, 0.f, 0.f}, {1.2345f, -2.f, 0.5f}};
  const EncodedPoints e = encodePoints(c, 0.001);
  EXPECT_GT(e.step_m, 0.001);  // 60 m do not fit 16 bits at 1 mm
  EXPECT_LE(e.step_m, 60.0 / 32767.0 + 1e-12);
  EXPECT_NEAR(decodePoints(e).points_S[0].x(), 60.f, e.step_m);
  const EncodedPoints f = encodePoints(c, 0.0);
  EXPECT_EQ(f.step_m, 0.0);
  EXPECT_EQ(decodePoints(f).points_S[1], c.points_S[1]);
}

TEST(ScanStoreTest, KeptPointsAreFloat32ByDefaultAndTheMapIsTheMapOfTheReceivedCloud) {
  EXPECT_EQ(ScanStoreParams().point_step_m, 0.0);
  PointCloud c = test::roomScan(4.0, 1.0, 2.0, 16, 360);
  c.points_S[3] = Eigen::Vector3f::Constant(std::numeric_limits<float>::quiet_NaN());
  MapParams plain;
  plain.backend = Backend::kCpu;
  MapParams kept = plain;
  kept.scans.keep = true;
  MapParams quantised = kept;
  quantised.scans.point_step_m = 0.001;
  Map without(plain), with(kept), coarse(quantised);
  for (int i = 0; i < 2; ++i) {
    without.insert(c, test::poseAt(i), test::lidar());
    with.insert(c, test::poseAt(i), test::lidar());
    coarse.insert(c, test::poseAt(i), test::lidar());
  }
  // Keeping scans does not change the map: it integrates the cloud as received.
  std::string why;
  EXPECT_TRUE(test::sameCells(with, without, &why)) << why;
  const EncodedPoints e = with.scanStore().points(1);
  EXPECT_EQ(e.step_m, 0.0);
  EXPECT_EQ(e.data.size(), c.size() * 12);
  EXPECT_EQ(with.scanStore().memoryBytes(), 2 * c.size() * 12);
  const PointCloud back = decodePoints(e);
  ASSERT_EQ(back.size(), c.size());
  EXPECT_EQ(0, std::memcmp(back.points_S.data(), c.points_S.data(), c.size() * 12));  // NaN too
  // The memory option: half the bytes, but the map is built from the quantised points and some
  // endpoints near a cell face land in the neighbouring cell.
  EXPECT_EQ(coarse.scanStore().memoryBytes(), 2 * c.size() * 6);
  EXPECT_FALSE(test::sameCells(coarse, without));
  const double same = test::sameState(coarse, without);
  EXPECT_LT(same, 1.0);
  EXPECT_GT(same, 0.99);
  // A removal from either store is exact (no clamping in two scans): the map of scan 0 alone.
  Map first(plain);
  first.insert(c, test::poseAt(0), test::lidar());
  with.remove(1);
  EXPECT_TRUE(test::sameCells(with, first, &why)) << why;
}

/// Four scans under a budget of a bit more than one scan's points at `step_m` (0: float32,
/// 12 bytes a point; else int16, 6): the three oldest go to the spill folder, come back
/// intact, and a correction from spilled points works; a damaged spill file is reported.
void expectBudgetSpills(double step_m) {
  SCOPED_TRACE("point step " + std::to_string(step_m));
  const std::string dir = std::string(FRAGG_TEST_TMP) + "/spill_test";
  std::filesystem::remove_all(dir);
  const PointCloud scan = test::roomScan(4, 1, 2, 8, 720);
  const size_t scan_bytes = scan.size() * (step_m > 0.0 ? 6 : 12);
  MapParams p;
  p.backend = Backend::kCpu;
  p.scans.keep = true;
  p.scans.point_step_m = step_m;
  p.scans.max_bytes = scan_bytes + scan_bytes / 6;
  p.scans.spill_dir = dir;
  Map map(p);
  MapParams plain_params = p;
  plain_params.scans = ScanStoreParams();
  Map plain(plain_params);
  for (int i = 0; i < 4; ++i) {
    map.insert(scan, test::poseAt(i), test::lidar());
    plain.insert(scan, test::poseAt(i), test::lidar());
  }
  EXPECT_EQ(map.scanStore().size(), 4u);
  EXPECT_EQ(map.scanStore().spilledCount(), 3u);
  EXPECT_EQ(map.scanStore().memoryBytes(), scan_bytes);  // the newest scan only
  const EncodedPoints back = map.scanStore().points(0);
  EXPECT_EQ(back.step_m, step_m);
  EXPECT_EQ(back.data, encodePoints(scan, step_m).data);
  if (step_m == 0.0) {
    EXPECT_EQ(decodePoints(back).points_S, scan.points_S);
    std::string why;
    EXPECT_TRUE(test::sameCells(map, plain, &why)) << why;
  }
  // A spilled scan is corrected from its spill file: moved away and back (no clamping in four
  // scans), the map is the one before.
  map.correctPoses({{1, test::poseAt(1, 0.4)}});
  EXPECT_FALSE(test::sameCells(map, plain));
  map.correctPoses({{1, test::poseAt(1)}});
  if (step_m == 0.0) {
    std::string why;
    EXPECT_TRUE(test::sameCells(map, plain, &why)) << why;
  }
  EXPECT_GT(test::sameState(map, plain), 0.99);
  // A spill file that was damaged is reported, not silently used.
  const std::string spilled = dir + "/scan_0.fgs";
  ASSERT_TRUE(std::filesystem::exists(spilled));
  std::filesystem::resize_file(spilled, std::filesystem::file_size(spilled) - 10);
  EXPECT_THROW(map.scanStore().points(0), IoError);
  const uint64_t revision = map.revision();
  EXPECT_THROW(map.correctPoses({{0, test::poseAt(0)}}), IoError);
  EXPECT_EQ(map.revision(), revision);  // nothing was integrated
}

TEST(ScanStoreTest, BudgetSpillsOldestScansToDiskAndReadsThemBack) {
  expectBudgetSpills(0.0);    // float32, the default
  expectBudgetSpills(0.001);  // quantised, the memory option
}

TEST(ScanStoreTest, WithoutSpillFolderTheOldestPointsAreDroppedAndThatIsAnError) {
  MapParams p;
  p.backend = Backend::kCpu;
  p.scans.keep = true;
  p.scans.max_bytes = 40000;
  Map map(p);
  for (int i = 0; i < 3; ++i)
    map.insert(test::roomScan(4, 1, 2, 8, 720), test::poseAt(i), test::lidar());
  EXPECT_GE(map.scanStore().droppedCount(), 1u);
  EXPECT_FALSE(map.scanStore().hasPoints(0));
  EXPECT_TRUE(map.scanStore().hasPoints(2));
  EXPECT_THROW(map.remove(0), InvalidArgument);
}

TEST(ScanStoreTest, KeptScansRoundTripThroughTheMapFile) {
  MapParams p;
  p.backend = Backend::kCpu;
  p.scans.keep = true;
  Map map(p);
  for (int i = 0; i < 3; ++i)
    map.insert(test::roomScan(4, 1, 2, 8, 180), test::poseAt(i), test::lidar(), 1000 + i,
               i == 1 ? "" : "lidar_" + std::to_string(i));
  EXPECT_THROW(map.insert(test::roomScan(4, 1, 2, 8, 180), test::poseAt(0), test::lidar(), 0,
                          std::string(kMaxSensorFrameChars + 1, 'f')),
               InvalidArgument);
  EXPECT_EQ(map.scanStore().size(), 3u);
  const std::string path = std::string(FRAGG_TEST_TMP) + "/kept_scans.fgm";
  map.save(path);
  Map loaded = Map::load(path, Backend::kCpu);
  ASSERT_EQ(loaded.scanStore().size(), 3u);
  for (ScanId id = 0; id < 3; ++id) {
    const ScanRecord& a = map.scanStore().record(id);
    const ScanRecord& b = loaded.scanStore().record(id);
    EXPECT_EQ(a.stamp_ns, b.stamp_ns);
    EXPECT_EQ(b.sensor_frame, id == 1 ? "" : "lidar_" + std::to_string(id));
    EXPECT_TRUE(a.T_map_sensor.matrix() == b.T_map_sensor.matrix());  // bit for bit
    EXPECT_EQ(a.model.type, b.model.type);
    EXPECT_EQ(a.model.max_range_m, b.model.max_range_m);
    EXPECT_EQ(map.scanStore().points(id).data, loaded.scanStore().points(id).data);
    // Float32 by default: the file gives back the points as they were received.
    EXPECT_EQ(loaded.scanStore().points(id).step_m, 0.0);
    EXPECT_EQ(decodePoints(loaded.scanStore().points(id)).points_S,
              test::roomScan(4, 1, 2, 8, 180).points_S);
  }
  // The loaded map keeps scans and numbers new ones after the old ones.
  EXPECT_EQ(loaded.insert(test::roomScan(4, 1, 2, 8, 180), test::poseAt(3), test::lidar()).scan_id,
            3u);
  // With runtime settings: the budget applies, and a map that keeps no scans drops the file's.
  MapParams budget = p;
  budget.scans.max_bytes = 1;  // everything but the newest scan is dropped
  budget.raycast = RayCast::kBresenham;
  Map bounded = Map::load(path, budget);
  EXPECT_EQ(bounded.params().raycast, RayCast::kBresenham);
  EXPECT_EQ(bounded.scanStore().size(), 3u);
  EXPECT_EQ(bounded.scanStore().droppedCount(), 2u);
  MapParams none = p;
  none.scans.keep = false;
  EXPECT_EQ(Map::load(path, none).scanStore().size(), 0u);
  // A truncated file with scans is rejected with a clear error.
  const auto size = std::filesystem::file_size(path);
  std::filesystem::resize_file(path, size - 100);
  EXPECT_THROW(Map::load(path, Backend::kCpu), IoError);
}

TEST(ScanStoreTest, MapsWithoutKeptScansStillWriteTheOldLayout) {
  MapParams p;
  p.backend = Backend::kCpu;
  Map map(p);
  map.insert(test::roomScan(4, 1, 2, 8, 180), test::poseAt(0), test::lidar());
  const std::string path = std::string(FRAGG_TEST_TMP) + "/no_scans.fgm";
  map.save(path);
  Map loaded = Map::load(path, Backend::kCpu);
  EXPECT_EQ(loaded.scanStore().size(), 0u);
  EXPECT_EQ(loaded.scanCount(), 1u);
  EXPECT_THROW(loaded.correctPoses({{0, test::poseAt(0)}}), InvalidArgument);
}

TEST(ScanStoreTest, ScanRecordsOfVersion2FilesReadWithoutRangeNoiseOrFrame) {
  ScanRecord r;
  r.id = 7;
  r.stamp_ns = 123;
  r.model = test::lidar();
  r.model.max_range_m = 10.0;
  r.model.range_noise_m = 0.0123;
  r.model.range_noise_quadratic_per_m = 0.000456;
  r.sensor_frame = "velodyne";
  r.points = 1;
  const EncodedPoints pts = encodePoints(test::roomScan(4, 1, 2, 4, 8), 0.001);
  r.points = pts.count;
  ByteWriter w;
  writeScan(w, r, pts);
  // The current format reads back with its noise.
  ScanRecord back;
  EncodedPoints back_pts;
  ByteReader current(w.bytes, w.bytes.size(), "mem", "scan");
  readScan(current, back, back_pts, kMapFileVersion);
  EXPECT_EQ(back.model.range_noise_m, 0.0123);
  EXPECT_EQ(back.model.range_noise_quadratic_per_m, 0.000456);
  EXPECT_EQ(back.sensor_frame, "velodyne");
  EXPECT_EQ(current.remaining(), 0u);
  // Version 2 wrote the same record without the noise and the frame (u16 length + chars):
  // read as no noise and no frame.
  const double noise[2] = {0.0123, 0.000456};
  auto at = std::search(w.bytes.begin(), w.bytes.end(), reinterpret_cast<const uint8_t*>(noise),
                        reinterpret_cast<const uint8_t*>(noise) + sizeof(noise));
  ASSERT_NE(at, w.bytes.end());
  const size_t v3_only = sizeof(noise) + sizeof(uint16_t) + r.sensor_frame.size();
  std::vector<uint8_t> v2(w.bytes.begin(), at);
  v2.insert(v2.end(), at + v3_only, w.bytes.end());
  ScanRecord old;
  EncodedPoints old_pts;
  ByteReader reader(v2, v2.size(), "mem", "scan");
  readScan(reader, old, old_pts, 2);
  EXPECT_EQ(old.model.range_noise_m, 0.0);
  EXPECT_EQ(old.model.range_noise_quadratic_per_m, 0.0);
  EXPECT_TRUE(old.sensor_frame.empty());
  EXPECT_EQ(old.model.max_range_m, 10.0);
  EXPECT_EQ(old_pts.data, pts.data);
  EXPECT_EQ(reader.remaining(), 0u);
  // A bad noise figure in a file is rejected like any other bad field.
  const double bad[2] = {-1.0, 0.0};
  std::vector<uint8_t> corrupt = w.bytes;
  std::memcpy(&corrupt[at - w.bytes.begin()], bad, sizeof(bad));
  ByteReader bad_reader(corrupt, corrupt.size(), "mem", "scan");
  EXPECT_THROW(readScan(bad_reader, old, old_pts, kMapFileVersion), IoError);
}

}  // namespace
}  // namespace fragg
