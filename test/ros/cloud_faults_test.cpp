// Faults on the map server's input path (cloud_inserter.h), without a ROS master: malformed
// PointCloud2 messages, all-NaN and huge finite points, unusable transforms, tf missing, from
// the future and older than the buffer, a cloud the map refuses. Each is counted under its own
// cause in ~stats, and the map is unchanged (revision and known cells); a good cloud after
// them is inserted.
#include <geometry_msgs/TransformStamped.h>
#include <gtest/gtest.h>
#include <ros/console.h>
#include <ros/time.h>

#include <cmath>
#include <limits>
#include <string>
#include <vector>

#include "../../src/ros/server/cloud_inserter.h"
#include "../core/extreme_points.h"
#include "cloud_msg_builder.h"
#include "fragg_map/errors.h"
#include "fragg_map/map.h"
#include "fragg_map/ros/cloud_from_msg.h"

namespace {

using fragg::ros::CloudFault;
using fragg::ros::CloudInserter;
using fragg::ros::ServerParams;
using fragg::ros::ServerStats;
using fragg::ros::SharedMap;
using fragg::ros::test::makeCloud;
using fragg::ros::test::packedXyz;
using F = sensor_msgs::PointField;

// A wall of points 3 m ahead (x), 0.1 m apart: a good cloud.
std::vector<Eigen::Vector3f> wall() {
  std::vector<Eigen::Vector3f> pts;
  for (int i = -10; i <= 10; ++i)
    for (int j = -5; j <= 5; ++j) pts.emplace_back(3.0f, 0.1f * i, 0.1f * j);
  return pts;
}

sensor_msgs::PointCloud2 goodMsg() {
  const auto pts = wall();
  return makeCloud(pts, static_cast<uint32_t>(pts.size()), 1, packedXyz(), 12);
}

class CloudFaultsTest : public ::testing::Test {
 protected:
  static void SetUpTestSuite() { ::ros::Time::init(); }  // the throttled log lines read it

  void SetUp() override {
    params_.map.backend = fragg::Backend::kCpu;
    params_.map.threads = 1;
    shared_ = std::make_unique<SharedMap>(fragg::ros::MapState(fragg::Map(params_.map)));
    inserter_ = std::make_unique<CloudInserter>(params_, shared_.get(), &stats_);
    // One good scan first: "unchanged" then means something.
    ASSERT_TRUE(offer(goodMsg(), Eigen::Isometry3d::Identity()));
    snapshot();
  }

  // Converts and inserts as CloudInput does once the transform is known.
  bool offer(const sensor_msgs::PointCloud2& msg, const Eigen::Isometry3d& T_map_sensor) {
    const auto cloud = inserter_->convert(msg);
    if (!cloud) return false;
    fragg::InsertStats inserted;
    return inserter_->insert(*cloud, T_map_sensor, 1000, msg.header.frame_id, &inserted);
  }

  void snapshot() {
    const SharedMap::ReadGuard state = shared_->read();
    revision_ = state->map.revision();
    known_ = state->map.knownVoxelCount();
    scans_ = state->map.scanCount();
  }

  void expectMapUnchanged() {
    const SharedMap::ReadGuard state = shared_->read();
    EXPECT_EQ(state->map.revision(), revision_);
    EXPECT_EQ(state->map.knownVoxelCount(), known_);
    EXPECT_EQ(state->map.scanCount(), scans_);
  }

  fragg_map::MapStats msg() const {
    const SharedMap::ReadGuard state = shared_->read();
    return stats_.toMsg(state->map, "map", ::ros::Time(0));
  }

  ServerParams params_;
  ServerStats stats_;
  std::unique_ptr<SharedMap> shared_;
  std::unique_ptr<CloudInserter> inserter_;
  uint64_t revision_ = 0, known_ = 0, scans_ = 0;
};

TEST_F(CloudFaultsTest, MalformedCloudsAreCountedAndLeaveTheMap) {
  std::vector<std::pair<std::string, sensor_msgs::PointCloud2>> bad;
  {
    auto m = goodMsg();
    m.fields.pop_back();  // no z
    bad.emplace_back("no z field", m);
  }
  {
    auto m = goodMsg();
    m.fields[1].datatype = F::INT16;
    bad.emplace_back("y of type int16", m);
  }
  {
    auto m = goodMsg();
    m.fields[0].datatype = 0;
    bad.emplace_back("x of datatype 0", m);
  }
  {
    auto m = goodMsg();
    m.fields[2].count = 0;
    bad.emplace_back("z with count 0", m);
  }
  {
    auto m = goodMsg();
    m.data.resize(m.data.size() - 1);
    bad.emplace_back("data one byte short", m);
  }
  {
    auto m = goodMsg();
    m.data.clear();
    bad.emplace_back("no data", m);
  }
  {
    // width x height overflows 32 bits (and any plausible memory): refused before allocating.
    auto m = goodMsg();
    m.width = 1u << 20;
    m.height = 1u << 16;
    m.row_step = m.width * 12;
    bad.emplace_back("width x height beyond the data (2^36 points)", m);
  }
  {
    auto m = goodMsg();
    m.width = 0xffffffffu;
    m.height = 0xffffffffu;
    m.row_step = 0xffffffffu;
    bad.emplace_back("width, height and row_step at 2^32 - 1", m);
  }
  {
    auto m = goodMsg();
    m.row_step = m.width * 12 - 1;
    bad.emplace_back("row_step shorter than a row", m);
  }
  {
    auto m = goodMsg();
    m.point_step = 8;
    m.row_step = m.width * 8;
    bad.emplace_back("point_step shorter than x y z", m);
  }
  {
    auto m = goodMsg();
    m.point_step = 0;
    m.row_step = 0;
    bad.emplace_back("point_step 0", m);
  }
  {
    auto m = goodMsg();
    m.header.frame_id = "";
    bad.emplace_back("no frame_id", m);
  }
  uint64_t n = 0;
  for (const auto& [what, m] : bad) {
    EXPECT_FALSE(offer(m, Eigen::Isometry3d::Identity())) << what;
    EXPECT_EQ(stats_.faults(CloudFault::kMalformed), ++n) << what;
    expectMapUnchanged();
  }
  const fragg_map::MapStats s = msg();
  EXPECT_EQ(s.rejected_malformed, bad.size());
  EXPECT_EQ(s.rejected_clouds, bad.size());
  EXPECT_EQ(s.dropped_clouds, bad.size());
  EXPECT_EQ(s.scans, 1u);
}

// Records every log line rosconsole emits at `min_level` or above while it is registered.
class LogRecorder : public ::ros::console::LogAppender {
 public:
  explicit LogRecorder(::ros::console::Level min_level) : min_level_(min_level) {
    ::ros::console::register_appender(this);
  }
  ~LogRecorder() override { ::ros::console::deregister_appender(this); }
  void log(::ros::console::Level level, const char* str, const char*, const char*, int) override {
    if (level >= min_level_) lines.emplace_back(str);
  }
  std::vector<std::string> lines;

 private:
  ::ros::console::Level min_level_;
};

TEST_F(CloudFaultsTest, EmptyCloudsAreCountedQuietlyNotAsFaults) {
  // Drivers publish empty clouds: counted in empty_clouds, no WARN or ERROR line, not a drop.
  std::vector<sensor_msgs::PointCloud2> empty;
  {
    auto m = goodMsg();
    m.width = 0;
    m.row_step = 0;
    m.data.clear();
    empty.push_back(m);
  }
  {
    auto m = goodMsg();
    m.height = 0;
    empty.push_back(m);
  }
  {
    auto m = goodMsg();  // fields that would be refused do not matter without points
    m.fields.clear();
    m.width = 0;
    m.data.clear();
    empty.push_back(m);
  }
  LogRecorder warnings(::ros::console::levels::Warn);
  for (const auto& m : empty) {
    EXPECT_FALSE(offer(m, Eigen::Isometry3d::Identity()));
    expectMapUnchanged();
  }
  EXPECT_TRUE(warnings.lines.empty()) << warnings.lines.front();
  const fragg_map::MapStats s = msg();
  EXPECT_EQ(s.empty_clouds, empty.size());
  EXPECT_EQ(s.rejected_malformed, 0u);
  EXPECT_EQ(s.rejected_clouds, 0u);
  EXPECT_EQ(s.dropped_clouds, 0u);
  stats_.restart(0);
  EXPECT_EQ(msg().empty_clouds, 0u);
}

TEST_F(CloudFaultsTest, AllNaNCloudIsNotCalledMalformed) {
  const float nan = std::numeric_limits<float>::quiet_NaN();
  const std::vector<Eigen::Vector3f> pts(6, Eigen::Vector3f::Constant(nan));
  const auto m = makeCloud(pts, 3, 2, packedXyz(), 12);
  try {
    fragg::ros::cloudFromMsg(m);
    FAIL() << "an all-NaN cloud was accepted";
  } catch (const fragg::InvalidArgument& e) {
    const std::string what = e.what();
    EXPECT_EQ(what.find("malformed"), std::string::npos) << what;
    EXPECT_NE(what.find("no finite point among 6"), std::string::npos) << what;
  }
  EXPECT_FALSE(offer(m, Eigen::Isometry3d::Identity()));
  const fragg_map::MapStats s = msg();
  EXPECT_EQ(s.rejected_no_finite_point, 1u);
  EXPECT_EQ(s.rejected_malformed, 0u);
  expectMapUnchanged();
}

TEST_F(CloudFaultsTest, BigEndianIsReadNotRefused) {
  // The same wall, big-endian: inserted, the same cells as the little-endian scan gives.
  auto m = goodMsg();
  for (size_t i = 0; i < m.data.size(); i += 4) std::reverse(&m.data[i], &m.data[i + 4]);
  m.is_bigendian = true;
  ASSERT_TRUE(offer(m, Eigen::Isometry3d::Identity()));
  const SharedMap::ReadGuard state = shared_->read();
  EXPECT_EQ(state->map.knownVoxelCount(), known_);  // the same rays again: no new cell
  EXPECT_EQ(state->map.scanCount(), scans_ + 1);
}

TEST_F(CloudFaultsTest, AllNaNAndOnlyHugePointsAreDroppedAsNoUsablePoint) {
  const float nan = std::numeric_limits<float>::quiet_NaN();
  const float inf = std::numeric_limits<float>::infinity();
  const std::vector<std::vector<Eigen::Vector3f>> clouds = {
      {Eigen::Vector3f::Constant(nan), Eigen::Vector3f(nan, 1, 1)},
      {Eigen::Vector3f(inf, 0, 0), Eigen::Vector3f(0, -inf, 0)},
      // The user's report: 4 points at 1e30 / -1e38 (finite floats).
      {Eigen::Vector3f(1e30f, 0, 0), Eigen::Vector3f(0, 1e30f, 0), Eigen::Vector3f(0, 0, -1e38f),
       Eigen::Vector3f(-1e38f, 1e30f, 0)},
      {Eigen::Vector3f::Zero(), Eigen::Vector3f::Zero()},
  };
  uint64_t n = 0;
  for (const auto& pts : clouds) {
    const auto m = makeCloud(pts, static_cast<uint32_t>(pts.size()), 1, packedXyz(), 12);
    EXPECT_FALSE(offer(m, Eigen::Isometry3d::Identity()));
    EXPECT_EQ(stats_.faults(CloudFault::kNoFinitePoint), ++n);
    expectMapUnchanged();
  }
  EXPECT_EQ(msg().points_invalid, 4u);  // the huge ones, left out before insertion
  EXPECT_EQ(msg().rejected_no_finite_point, clouds.size());
}

// Every block of the map lies within `reach_m` of the origin (the sensor).
void expectBlocksWithin(const fragg::Map& map, double reach_m) {
  const double block_m = 8 * map.resolution();
  map.forEachBlock([&](const fragg::BlockKey& key, const fragg::Block&) {
    const int32_t k[3] = {key.x, key.y, key.z};
    for (int a = 0; a < 3; ++a) {
      const double lo = k[a] * block_m, hi = lo + block_m;
      EXPECT_LE(std::max(std::abs(lo), std::abs(hi)), reach_m + block_m) << "axis " << a;
    }
  });
}

TEST_F(CloudFaultsTest, HugeFinitePointsAmongGoodOnesAreCutOrLeftOutAndCounted) {
  ASSERT_GT(params_.sensor.max_range_m, 0.0) << "the server's default max_range is finite";
  auto pts = wall();
  // Beyond the map's key range (5 cm: 2^30 voxels = 5.4e7 m): left out, counted invalid.
  pts.emplace_back(1e30f, 0, 0);
  pts.emplace_back(0, 0, -1e38f);
  // Within the key range but far beyond max_range: free space cleared up to max_range only.
  pts.emplace_back(1e6f, 1e6f, 0);
  pts.emplace_back(-3e5f, 0, 2e5f);
  const auto m = makeCloud(pts, static_cast<uint32_t>(pts.size()), 1, packedXyz(), 12);
  ASSERT_TRUE(offer(m, Eigen::Isometry3d::Identity()));
  const fragg_map::MapStats s = msg();
  EXPECT_EQ(s.points_invalid, 2u);
  EXPECT_EQ(s.points_beyond_range, 2u);
  const SharedMap::ReadGuard state = shared_->read();
  expectBlocksWithin(state->map, params_.sensor.max_range_m);
}

TEST_F(CloudFaultsTest, UnlimitedRangeIsNotStretchedByPointsBeyondTheKeyRange) {
  // octomap_server's max_range -1 (no limit): the map's auto range is the farthest point,
  // which must not be one the map cannot hold.
  params_.sensor.max_range_m = -1.0;
  CloudInserter unlimited(params_, shared_.get(), &stats_);
  auto pts = wall();
  pts.emplace_back(1e30f, 0, 0);
  pts.emplace_back(0, -1e38f, 0);
  const auto m = makeCloud(pts, static_cast<uint32_t>(pts.size()), 1, packedXyz(), 12);
  const auto cloud = unlimited.convert(m);
  ASSERT_TRUE(cloud);
  EXPECT_EQ(cloud->size(), wall().size());
  fragg::InsertStats inserted;
  ASSERT_TRUE(unlimited.insert(*cloud, Eigen::Isometry3d::Identity(), 2000, "sensor", &inserted));
  EXPECT_LE(inserted.sensor.max_range_m, 4.0);  // the wall's farthest point, rounded up
  const SharedMap::ReadGuard state = shared_->read();
  expectBlocksWithin(state->map, 4.0);
}

TEST_F(CloudFaultsTest, OrganisedCloudsKeepTheirShapeWhenHugePointsGo) {
  auto pts = wall();  // 21 x 11
  pts[5] = Eigen::Vector3f(1e30f, 0, 0);
  const auto m = makeCloud(pts, 21, 11, packedXyz(), 12);
  const auto cloud = inserter_->convert(m);
  ASSERT_TRUE(cloud);
  EXPECT_TRUE(cloud->organised());
  EXPECT_EQ(cloud->size(), pts.size());
  EXPECT_FALSE(cloud->points_S[5].allFinite());
}

TEST_F(CloudFaultsTest, UnusableTransformsAreCountedAndLeaveTheMap) {
  const double nan = std::numeric_limits<double>::quiet_NaN();
  std::vector<std::pair<std::string, Eigen::Isometry3d>> bad;
  Eigen::Isometry3d T = Eigen::Isometry3d::Identity();
  T.translation() = Eigen::Vector3d(nan, 0, 0);
  bad.emplace_back("NaN translation", T);
  T = Eigen::Isometry3d::Identity();
  T.linear()(0, 0) = std::numeric_limits<double>::infinity();
  bad.emplace_back("Inf in the rotation", T);
  T = Eigen::Isometry3d::Identity();
  T.linear() *= 2.0;  // a scaling, not a rotation (an unnormalised quaternion)
  bad.emplace_back("scaled rotation", T);
  T = Eigen::Isometry3d::Identity();
  T.linear()(2, 2) = -1.0;  // a reflection
  bad.emplace_back("reflection", T);
  T = Eigen::Isometry3d::Identity();
  T.translation() = Eigen::Vector3d(1e12, 0, 0);
  bad.emplace_back("sensor beyond the key range", T);
  uint64_t n = 0;
  for (const auto& [what, T_bad] : bad) {
    EXPECT_FALSE(offer(goodMsg(), T_bad)) << what;
    EXPECT_EQ(stats_.faults(CloudFault::kBadTransform), ++n) << what;
    expectMapUnchanged();
  }
  EXPECT_EQ(msg().rejected_bad_transform, bad.size());
}

TEST_F(CloudFaultsTest, ACloudTheMapRefusesIsAnInsertionFailure) {
  // The map throws (a sensor frame name longer than a .fgm can hold): caught, counted, the map
  // as it was; the next good cloud goes in.
  auto m = goodMsg();
  m.header.frame_id = std::string(100000, 'f');
  EXPECT_FALSE(offer(m, Eigen::Isometry3d::Identity()));
  EXPECT_EQ(stats_.faults(CloudFault::kInsertFailed), 1u);
  expectMapUnchanged();
  EXPECT_EQ(msg().insertion_failures, 1u);
  EXPECT_TRUE(offer(goodMsg(), Eigen::Isometry3d::Identity()));
  EXPECT_EQ(msg().scans, 2u);
}

TEST_F(CloudFaultsTest, ExtremeFinitePointsLeaveTheMapAsTheGoodPointsMakeIt) {
  // Issue 39: one finite point with a huge coordinate and a tiny non-zero other one crashed the
  // insertion (the server died the same way as `fragg_map build`). These points with the wall:
  // the cloud is inserted, every point is counted, the wall's hit cells are as the wall alone
  // makes them, no block lies beyond max range, and ~get_stats (the stats message) answers.
  const std::vector<Eigen::Vector3f>& extreme = fragg::test::extremePoints();
  std::vector<std::pair<fragg::VoxelKey, fragg::Cell>> wall_hits;
  {
    const SharedMap::ReadGuard state = shared_->read();
    state->map.forEachBlock([&](const fragg::BlockKey& key, const fragg::Block& block) {
      for (int c = 0; c < fragg::kCellsPerBlock; ++c)
        if (block.cells[c].hits > 0)
          wall_hits.emplace_back(fragg::voxelKeyOf(key, c), block.cells[c]);
    });
  }
  ASSERT_FALSE(wall_hits.empty());
  const uint64_t points_before = msg().points;
  auto pts = extreme;
  const auto m = makeCloud(pts, static_cast<uint32_t>(pts.size()), 1, packedXyz(), 12);
  ASSERT_TRUE(offer(m, Eigen::Isometry3d::Identity()));
  const fragg_map::MapStats s = msg();
  EXPECT_EQ(s.scans, 2u);
  EXPECT_EQ(s.points - points_before + s.points_invalid, extreme.size())
      << "points given to the map and points left out before it";
  const SharedMap::ReadGuard state = shared_->read();
  for (const auto& [key, cell] : wall_hits) {
    const fragg::Cell* now = state->map.findCell(key);
    ASSERT_NE(now, nullptr);
    EXPECT_EQ(now->log_odds_fx, cell.log_odds_fx);
    EXPECT_EQ(now->hits, cell.hits);
  }
  expectBlocksWithin(state->map, params_.sensor.max_range_m);
}

// tf: a buffer with map <- sensor at t = 10..20 s (10 s cache, as tf2_ros's default).
class TfFaultsTest : public ::testing::Test {
 protected:
  void SetUp() override {
    for (int t = 10; t <= 20; ++t) {
      geometry_msgs::TransformStamped tf;
      tf.header.frame_id = "map";
      tf.header.stamp = ::ros::Time(t);
      tf.child_frame_id = "sensor";
      tf.transform.translation.x = 0.1 * t;
      tf.transform.rotation.w = 1.0;
      ASSERT_TRUE(buffer_.setTransform(tf, "test"));
    }
  }
  fragg::ros::TfWait wait(const std::string& source, double stamp_s, double tolerance_s) {
    error_.clear();
    return fragg::ros::waitForTransform(buffer_, "map", source, ::ros::Time(stamp_s), tolerance_s,
                                        stop_, &T_, &error_);
  }
  tf2::BufferCore buffer_{::ros::Duration(10.0)};
  std::atomic<bool> stop_{false};
  Eigen::Isometry3d T_ = Eigen::Isometry3d::Identity();
  std::string error_;
};

TEST_F(TfFaultsTest, FoundWithinTheBuffer) {
  EXPECT_EQ(wait("sensor", 15.5, 0.0), fragg::ros::TfWait::kFound);
  EXPECT_NEAR(T_.translation().x(), 1.55, 1e-9);
}

TEST_F(TfFaultsTest, MissingFrameTimesOut) {
  EXPECT_EQ(wait("lidar", 15.0, 0.05), fragg::ros::TfWait::kTimedOut);
  EXPECT_FALSE(error_.empty());
}

TEST_F(TfFaultsTest, FromTheFutureTimesOut) {
  EXPECT_EQ(wait("sensor", 1e6, 0.05), fragg::ros::TfWait::kTimedOut);
  EXPECT_NE(error_.find("future"), std::string::npos) << error_;
}

TEST_F(TfFaultsTest, OlderThanTheBufferIsDroppedWithoutWaiting) {
  const auto t0 = std::chrono::steady_clock::now();
  EXPECT_EQ(wait("sensor", 1.0, 30.0), fragg::ros::TfWait::kTooOld);  // would wait 30 s
  EXPECT_LT(std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count(), 10.0);
}

TEST_F(TfFaultsTest, BeforeAFramesOnlyTransformIsTooOldAfterItTimesOut) {
  // A frame with one transform: tf2 says "only time ... is in the buffer", not "into the past".
  geometry_msgs::TransformStamped tf;
  tf.header.frame_id = "map";
  tf.header.stamp = ::ros::Time(15);
  tf.child_frame_id = "once";
  tf.transform.rotation.w = 1.0;
  ASSERT_TRUE(buffer_.setTransform(tf, "test"));
  EXPECT_EQ(wait("once", 14.0, 30.0), fragg::ros::TfWait::kTooOld) << error_;
  EXPECT_EQ(wait("once", 16.0, 0.05), fragg::ros::TfWait::kTimedOut) << error_;
  EXPECT_FALSE(fragg::ros::stampBeforeBuffer("frame does not exist"));
}

TEST_F(TfFaultsTest, NonFiniteTransformsNeverEnterTheBuffer) {
  geometry_msgs::TransformStamped tf;
  tf.header.frame_id = "map";
  tf.header.stamp = ::ros::Time(15);
  tf.child_frame_id = "nan_sensor";
  tf.transform.translation.x = std::numeric_limits<double>::quiet_NaN();
  tf.transform.rotation.w = 1.0;
  EXPECT_FALSE(buffer_.setTransform(tf, "test"));
  EXPECT_EQ(wait("nan_sensor", 15.0, 0.05), fragg::ros::TfWait::kTimedOut);
}

TEST_F(TfFaultsTest, StopEndsTheWait) {
  stop_ = true;
  EXPECT_EQ(wait("lidar", 15.0, 30.0), fragg::ros::TfWait::kStopped);
}

}  // namespace
