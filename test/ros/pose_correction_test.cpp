// The ROS-free rules of the map server's loop-closure correction: the stamp index (nearest
// stamp within a tolerance), pose checks, the pose-change thresholds, path pose -> sensor pose,
// and the correction plan against a real scan store.
#include "fragg_map/ros/pose_correction.h"

#include <gtest/gtest.h>

#include <cmath>
#include <limits>

#include "fragg_map/errors.h"
#include "fragg_map/map.h"
#include "fragg_map/ros/scan_stamp_index.h"
#include "map_fixtures.h"

namespace {

using fragg::ros::PoseRequest;
using fragg::ros::PoseThresholds;
using fragg::ros::ScanStampIndex;

constexpr int64_t kMs = 1000000;  // ns

Eigen::Isometry3d pose(double x, double y, double z, double yaw_rad = 0.0) {
  Eigen::Isometry3d T = Eigen::Isometry3d::Identity();
  T.linear() = Eigen::AngleAxisd(yaw_rad, Eigen::Vector3d::UnitZ()).toRotationMatrix();
  T.translation() = Eigen::Vector3d(x, y, z);
  return T;
}

geometry_msgs::Pose poseMsg(double x, double qx, double qy, double qz, double qw) {
  geometry_msgs::Pose p;
  p.position.x = x;
  p.orientation.x = qx;
  p.orientation.y = qy;
  p.orientation.z = qz;
  p.orientation.w = qw;
  return p;
}

TEST(ScanStampIndex, FindsTheNearestStampWithinTheTolerance) {
  ScanStampIndex index;
  index.add(100 * kMs, 0, "lidar");
  index.add(200 * kMs, 1, "lidar");
  index.add(300 * kMs, 2, "camera");
  ASSERT_NE(index.find(200 * kMs, 0), nullptr);
  EXPECT_EQ(index.find(200 * kMs, 0)->id, 1u);
  EXPECT_EQ(index.find(300 * kMs, 0)->sensor_frame, "camera");
  EXPECT_EQ(index.find(199 * kMs, 0), nullptr);            // exact match required at 0
  EXPECT_EQ(index.find(199 * kMs, 1 * kMs)->id, 1u);       // the tolerance is inclusive
  EXPECT_EQ(index.find(199 * kMs - 1, 1 * kMs), nullptr);  // 1 ns beyond it
  EXPECT_EQ(index.find(240 * kMs, 50 * kMs)->id, 1u);      // nearest of 1 and 2
  EXPECT_EQ(index.find(260 * kMs, 50 * kMs)->id, 2u);
  EXPECT_EQ(index.find(250 * kMs, 50 * kMs)->id, 1u);  // a tie: the earlier stamp
  EXPECT_EQ(index.find(0, 99 * kMs), nullptr);         // before the first
  EXPECT_EQ(index.find(301 * kMs, 1 * kMs)->id, 2u);   // after the last
  EXPECT_EQ(index.find(200 * kMs, -1), nullptr);
  EXPECT_EQ(index.find(std::numeric_limits<int64_t>::max(), 1 * kMs), nullptr);  // no overflow
  index.add(200 * kMs, 7, "lidar");  // the same stamp again names the newer scan
  EXPECT_EQ(index.find(200 * kMs, 0)->id, 7u);
  EXPECT_EQ(index.size(), 3u);
  index.clear();
  EXPECT_EQ(index.find(200 * kMs, 1000 * kMs), nullptr);
}

TEST(PoseCorrection, IsometryFromPoseChecksAndNormalises) {
  const double h = std::sqrt(0.5);
  const Eigen::Isometry3d T = fragg::ros::isometryFromPose(poseMsg(2.0, 0, 0, h, h));
  EXPECT_TRUE(T.translation().isApprox(Eigen::Vector3d(2, 0, 0)));
  EXPECT_TRUE((T.linear() * Eigen::Vector3d::UnitX()).isApprox(Eigen::Vector3d::UnitY(), 1e-12));
  // Within 1e-3 of unit norm: accepted and normalised.
  const Eigen::Isometry3d N = fragg::ros::isometryFromPose(poseMsg(0, 0, 0, 0, 1.0005));
  EXPECT_NEAR(N.linear().determinant(), 1.0, 1e-12);
  const double nan = std::numeric_limits<double>::quiet_NaN();
  EXPECT_THROW(fragg::ros::isometryFromPose(poseMsg(nan, 0, 0, 0, 1)), fragg::InvalidArgument);
  EXPECT_THROW(fragg::ros::isometryFromPose(poseMsg(0, 0, 0, nan, 1)), fragg::InvalidArgument);
  EXPECT_THROW(fragg::ros::isometryFromPose(poseMsg(0, 0, 0, 0, 0)), fragg::InvalidArgument);
  EXPECT_THROW(fragg::ros::isometryFromPose(poseMsg(0, 0, 0, 0, 2)), fragg::InvalidArgument);
  EXPECT_THROW(fragg::ros::isometryFromPose(poseMsg(0, 0, 0, 0, 1.01)), fragg::InvalidArgument);
}

TEST(PoseCorrection, PoseMovedUsesBothThresholds) {
  const PoseThresholds t{0.05, 0.01};
  const Eigen::Isometry3d A = pose(1, 2, 3, 0.5);
  EXPECT_FALSE(fragg::ros::poseMoved(A, A, t));
  EXPECT_FALSE(fragg::ros::poseMoved(A, pose(1.04, 2, 3, 0.5), t));
  EXPECT_TRUE(fragg::ros::poseMoved(A, pose(1.06, 2, 3, 0.5), t));
  EXPECT_TRUE(fragg::ros::poseMoved(A, pose(1, 2, 2.94, 0.5), t));
  EXPECT_FALSE(fragg::ros::poseMoved(A, pose(1, 2, 3, 0.509), t));
  EXPECT_TRUE(fragg::ros::poseMoved(A, pose(1, 2, 3, 0.511), t));
  EXPECT_TRUE(fragg::ros::poseMoved(A, pose(1, 2, 3, 0.5 - 0.011), t));  // either direction
  // A rotation about another axis counts by its angle too.
  Eigen::Isometry3d R = A;
  R.linear() = A.linear() * Eigen::AngleAxisd(0.02, Eigen::Vector3d::UnitX()).toRotationMatrix();
  EXPECT_TRUE(fragg::ros::poseMoved(A, R, t));
  EXPECT_FALSE(fragg::ros::poseMoved(A, R, PoseThresholds{0.05, 0.03}));
  // Zero thresholds: any change moves, no change does not.
  EXPECT_TRUE(fragg::ros::poseMoved(A, pose(1, 2, 3.001, 0.5), PoseThresholds{0.0, 0.0}));
  EXPECT_FALSE(fragg::ros::poseMoved(A, A, PoseThresholds{0.0, 0.0}));
}

TEST(PoseCorrection, SensorPoseFromPathPoseOfAnotherFrame) {
  // base_link at (1, 0, 0) turned 90 degrees left; the sensor 0.5 m ahead and 1 m up on it.
  const Eigen::Isometry3d T_map_base = pose(1, 0, 0, M_PI / 2);
  const Eigen::Isometry3d T_base_sensor = pose(0.5, 0, 1, 0.0);
  const Eigen::Isometry3d T = fragg::ros::sensorPoseFromChild(T_map_base, T_base_sensor);
  EXPECT_TRUE(T.translation().isApprox(Eigen::Vector3d(1, 0.5, 1), 1e-12));
  EXPECT_TRUE(T.linear().isApprox(T_map_base.linear(), 1e-12));
  // Identity child -> sensor: the path pose is the sensor pose.
  EXPECT_TRUE(fragg::ros::sensorPoseFromChild(T_map_base, Eigen::Isometry3d::Identity())
                  .isApprox(T_map_base));
}

// A map keeping three wall scans stamped 1, 2 and 3 s, and their index.
class CorrectionPlanTest : public ::testing::Test {
 protected:
  void SetUp() override { build(fragg::ScanStoreParams{true, 0.001, 0, ""}); }

  void build(const fragg::ScanStoreParams& scans) {
    fragg::MapParams p = fragg::ros::test::cpuParams();
    p.scans = scans;
    map_ = std::make_unique<fragg::Map>(p);
    index_.clear();
    for (int i = 0; i < 3; ++i) {
      fragg::PointCloud cloud;
      for (int k = 0; k < 100; ++k) cloud.points_S.emplace_back(3.f, -1.f + 0.02f * k, 0.f);
      const int64_t stamp_ns = (i + 1) * 1000 * kMs;
      const fragg::InsertStats s = map_->insert(
          cloud, pose(0, i, 0), fragg::SensorModel::autoFromCloud(0, -1), stamp_ns, "lidar");
      index_.add(stamp_ns, s.scan_id, "lidar");
    }
  }

  std::unique_ptr<fragg::Map> map_;
  ScanStampIndex index_;
};

TEST_F(CorrectionPlanTest, MatchesStampsAndReportsTheUnknown) {
  const std::vector<PoseRequest> requests = {
      {1000 * kMs + 200000, pose(0.5, 0, 0)},  // scan 0, 0.2 ms off
      {5000 * kMs, pose(0, 0, 0)},             // no scan
      {3000 * kMs, pose(0.5, 2, 0)},           // scan 2
  };
  const fragg::ros::CorrectionPlan plan =
      fragg::ros::planCorrection(requests, index_, map_->scanStore(), 1 * kMs, nullptr);
  ASSERT_EQ(plan.T_map_sensor_new.size(), 2u);
  EXPECT_TRUE(plan.T_map_sensor_new.at(0).isApprox(pose(0.5, 0, 0)));
  EXPECT_TRUE(plan.T_map_sensor_new.at(2).isApprox(pose(0.5, 2, 0)));
  ASSERT_EQ(plan.unknown.size(), 1u);
  EXPECT_EQ(plan.unknown[0], 1u);
  // The plan is what Map::correctPoses takes.
  EXPECT_EQ(map_->correctPoses(plan.T_map_sensor_new).scans, 2u);
  EXPECT_TRUE(map_->scanStore().record(2).T_map_sensor.isApprox(pose(0.5, 2, 0)));
  // A tighter tolerance: the 0.2 ms offset no longer matches.
  const fragg::ros::CorrectionPlan strict =
      fragg::ros::planCorrection(requests, index_, map_->scanStore(), 100000, nullptr);
  EXPECT_EQ(strict.T_map_sensor_new.size(), 1u);
  EXPECT_EQ(strict.unknown.size(), 2u);
}

TEST_F(CorrectionPlanTest, UnknownStampsSayWhy) {
  // Scan 2 (stamp 3 s, sensor at y 2) reached by an edit: a box clear within its rays' reach
  // (3.2 m around the sensor) beyond the other scans' (y 4.5-5): no longer correctable, scan 0
  // untouched.
  map_->clearBox(Eigen::Vector3d(-1.0, 4.5, -1.0), Eigen::Vector3d(1.0, 5.0, 1.0));
  ASSERT_FALSE(map_->scanStore().canRemove(2));
  ASSERT_TRUE(map_->scanStore().canRemove(0));
  const std::vector<PoseRequest> requests = {
      {1000 * kMs, pose(0.5, 0, 0)},  // scan 0: corrected
      {3000 * kMs, pose(0.5, 2, 0)},  // scan 2: edited
      {7000 * kMs, pose(0, 0, 0)},    // no scan
      {9000 * kMs, pose(0, 0, 0)},    // no scan
  };
  const fragg::ros::CorrectionPlan plan =
      fragg::ros::planCorrection(requests, index_, map_->scanStore(), 1 * kMs, nullptr);
  EXPECT_EQ(plan.unknown.size(), 3u);
  EXPECT_EQ(plan.unknown_no_scan, 2u);
  EXPECT_EQ(plan.unknown_not_kept, 0u);
  EXPECT_EQ(plan.unknown_edited, 1u);
  EXPECT_EQ(fragg::ros::describeUnknown(plan),
            "3 stamps name no scan that can be corrected: 2 match no scan within "
            "correction/stamp_tolerance; 1 names a scan an edit reached (clear_bbox / clear_bbx, "
            "truncate, merge: the updates can no longer be undone exactly)");
  fragg::ros::CorrectionPlan none;
  EXPECT_EQ(fragg::ros::describeUnknown(none), "0 stamps name no scan that can be corrected");
}

TEST_F(CorrectionPlanTest, ScansWhosePointsTheBudgetDroppedAreNamedAsNotKept) {
  // A budget of one byte and no spill folder: the points of every scan but the newest (scan
  // 2) are dropped.
  build(fragg::ScanStoreParams{true, 0.001, 1, ""});
  const std::vector<PoseRequest> requests = {{1000 * kMs, pose(0.5, 0, 0)}};
  const fragg::ros::CorrectionPlan plan =
      fragg::ros::planCorrection(requests, index_, map_->scanStore(), 1 * kMs, nullptr);
  ASSERT_EQ(plan.unknown.size(), 1u);
  EXPECT_EQ(plan.unknown_not_kept, 1u);
  EXPECT_NE(fragg::ros::describeUnknown(plan).find("1 names a scan no longer kept"),
            std::string::npos);
}

TEST_F(CorrectionPlanTest, ThresholdsLeaveSmallChangesAlone) {
  const PoseThresholds t{0.05, 0.01};
  const std::vector<PoseRequest> requests = {
      {1000 * kMs, pose(0.01, 0, 0)},    // 1 cm: unchanged
      {2000 * kMs, pose(0, 1.2, 0)},     // 20 cm: moved
      {3000 * kMs, pose(0, 2, 0, 0.1)},  // turned: moved
  };
  const fragg::ros::CorrectionPlan plan =
      fragg::ros::planCorrection(requests, index_, map_->scanStore(), 0, &t);
  EXPECT_EQ(plan.unchanged, 1u);
  EXPECT_EQ(plan.T_map_sensor_new.size(), 2u);
  EXPECT_EQ(plan.T_map_sensor_new.count(0), 0u);
  EXPECT_TRUE(plan.unknown.empty());
  // Without thresholds every matched scan is planned.
  EXPECT_EQ(fragg::ros::planCorrection(requests, index_, map_->scanStore(), 0, nullptr)
                .T_map_sensor_new.size(),
            3u);
}

TEST_F(CorrectionPlanTest, TwoRequestsForOneScanAreRefused) {
  const std::vector<PoseRequest> requests = {{2000 * kMs, pose(0, 1, 0)},
                                             {2000 * kMs + 10, pose(0, 1.5, 0)}};
  EXPECT_THROW(fragg::ros::planCorrection(requests, index_, map_->scanStore(), 1 * kMs, nullptr),
               fragg::InvalidArgument);
}

TEST_F(CorrectionPlanTest, ScansWhosePointsWereDroppedAreUnknown) {
  // A budget of one scan's points and no spill folder: the two oldest scans lose theirs.
  build(fragg::ScanStoreParams{true, 0.001, 700, ""});
  EXPECT_EQ(map_->scanStore().droppedCount(), 2u);
  const std::vector<PoseRequest> requests = {
      {1000 * kMs, pose(0.5, 0, 0)}, {2000 * kMs, pose(0.5, 1, 0)}, {3000 * kMs, pose(0.5, 2, 0)}};
  const fragg::ros::CorrectionPlan plan =
      fragg::ros::planCorrection(requests, index_, map_->scanStore(), 0, nullptr);
  EXPECT_EQ(plan.T_map_sensor_new.size(), 1u);
  EXPECT_EQ(plan.T_map_sensor_new.count(2), 1u);
  EXPECT_EQ(plan.unknown, (std::vector<size_t>{0, 1}));
}

TEST_F(CorrectionPlanTest, IndexRebuiltFromTheStoreMatchesByStamp) {
  ScanStampIndex rebuilt;
  rebuilt.rebuild(map_->scanStore());
  EXPECT_EQ(rebuilt.size(), 3u);
  ASSERT_NE(rebuilt.find(2000 * kMs, 0), nullptr);
  EXPECT_EQ(rebuilt.find(2000 * kMs, 0)->id, 1u);
  // The store keeps each scan's frame id, so a map loaded from a file finds its sensors again.
  EXPECT_EQ(rebuilt.find(2000 * kMs, 0)->sensor_frame, "lidar");
}

}  // namespace
