// ROS bag reader on bags written at test time by make_test_bag.py from the real small_gicp
// Velodyne scans: topic detection, float32/float64 and organised clouds, poses from /tf and
// /tf_static at each cloud's stamp, skipped clouds, damaged bags.
#include "fragg_map/io/rosbag_source.h"

#include <gtest/gtest.h>

#include <cstdlib>
#include <fstream>
#include <sstream>
#include <string>
#include <vector>

#include "fragg_map/errors.h"
#include "fragg_map/io/dataset.h"
#include "fragg_map/io/point_file.h"
#include "io_test_util.h"

namespace fragg {
namespace {

using test::expectIoError;
using test::realData;

struct ExpectedPose {
  int64_t stamp_ns = 0;
  Eigen::Isometry3d T_map_sensor = Eigen::Isometry3d::Identity();
};

// Writes a bag with make_test_bag.py; returns its path. Expected poses come from its sidecar.
std::string makeBag(const std::string& dir, const std::string& variant,
                    std::vector<ExpectedPose>* poses = nullptr) {
  const std::string path = dir + "/" + variant + ".bag";
  const std::string command = std::string(FRAGG_PYTHON3) + " '" + FRAGG_MAKE_TEST_BAG + "' '" +
                              path + "' '" + realData("small_gicp_pair") + "' --variant " + variant;
  EXPECT_EQ(std::system(command.c_str()), 0) << command;
  if (poses) {
    std::ifstream in(path + ".poses");
    ExpectedPose pose;
    while (in >> pose.stamp_ns) {
      Eigen::Matrix4d m;
      for (int r = 0; r < 4; ++r)
        for (int c = 0; c < 4; ++c) in >> m(r, c);
      pose.T_map_sensor = Eigen::Isometry3d(m);
      poses->push_back(pose);
    }
    EXPECT_EQ(poses->size(), 2u);
  }
  return path;
}

Eigen::Isometry3d readMatrix4(const std::string& path) {
  std::ifstream in(path);
  Eigen::Matrix4d m;
  for (int r = 0; r < 4; ++r)
    for (int c = 0; c < 4; ++c) in >> m(r, c);
  return Eigen::Isometry3d(m);
}

class RosbagTest : public ::testing::Test {
 protected:
  void SetUp() override {
    registerRosbagReader();
    dir_ = test::scratchDir();
  }
  void TearDown() override { registerBagOpener(nullptr); }
  std::string dir_;
};

TEST_F(RosbagTest, CloudsPosedFromTfAtTheirStamps) {
  std::vector<ExpectedPose> expected;
  const std::string bag = makeBag(dir_, "normal", &expected);
  ASSERT_EQ(expected.size(), 2u);
  auto source = openDataset(bag);  // topic auto-detected, frame "map"
  EXPECT_EQ(source->size(), std::optional<size_t>(3));
  EXPECT_NE(source->describe().find("/velodyne_points"), std::string::npos);

  const PointCloud target = readPly(realData("small_gicp_pair/target.ply"));
  const PointCloud source_ply = readPly(realData("small_gicp_pair/source.ply"));
  std::vector<Eigen::Vector3f> target_valid;
  for (const Eigen::Vector3f& p : target.points_S)
    if (p.allFinite()) target_valid.push_back(p);

  Scan scan;
  // 1: float32, unorganised, no-return points dropped by the "driver".
  ASSERT_TRUE(source->next(scan));
  EXPECT_EQ(scan.stamp_ns, expected[0].stamp_ns);
  EXPECT_FALSE(scan.cloud.organised());
  ASSERT_EQ(scan.cloud.size(), target_valid.size());
  for (size_t i = 0; i < target_valid.size(); ++i)
    ASSERT_EQ(scan.cloud.points_S[i], target_valid[i]) << "point " << i;
  EXPECT_TRUE(scan.T_map_sensor.matrix().isApprox(expected[0].T_map_sensor.matrix(), 1e-9))
      << scan.T_map_sensor.matrix() << "\nexpected\n"
      << expected[0].T_map_sensor.matrix();
  const Eigen::Isometry3d T_map_sensor_1 = scan.T_map_sensor;

  // 2: float64 x y z, organised 32 rows with NaN where there was no return.
  ASSERT_TRUE(source->next(scan));
  EXPECT_EQ(scan.stamp_ns, expected[1].stamp_ns);
  ASSERT_TRUE(scan.cloud.organised());
  EXPECT_EQ(scan.cloud.height, 32u);
  EXPECT_EQ(scan.cloud.width, 69792u / 32u);
  ASSERT_EQ(scan.cloud.size(), source_ply.size());
  size_t nan = 0;
  for (size_t i = 0; i < scan.cloud.size(); ++i) {
    const Eigen::Vector3f& a = scan.cloud.points_S[i];
    const Eigen::Vector3f& b = source_ply.points_S[i];
    if (b.hasNaN()) {
      ASSERT_TRUE(a.hasNaN()) << "point " << i;
      ++nan;
    } else {
      ASSERT_EQ(a, b) << "point " << i;
    }
  }
  EXPECT_EQ(nan, 5107u);
  EXPECT_TRUE(scan.T_map_sensor.matrix().isApprox(expected[1].T_map_sensor.matrix(), 1e-9))
      << scan.T_map_sensor.matrix() << "\nexpected\n"
      << expected[1].T_map_sensor.matrix();
  // The two poses relate as the pair's registration says (the scans align in the map).
  const Eigen::Isometry3d T_target_source =
      readMatrix4(realData("small_gicp_pair/T_target_source.txt"));
  EXPECT_TRUE(
      scan.T_map_sensor.matrix().isApprox((T_map_sensor_1 * T_target_source).matrix(), 1e-5));

  // 3: stamped after the last /tf message: skipped and counted, not silently posed.
  EXPECT_FALSE(source->next(scan));
  EXPECT_EQ(source->skipped(), 1u);
  EXPECT_NE(source->lastSkipReason().find("xtrapolation"), std::string::npos)
      << source->lastSkipReason();
}

TEST_F(RosbagTest, TopicAndFrameOptions) {
  const std::string bag = makeBag(dir_, "normal");
  DatasetOptions options;
  options.topic = "velodyne_points";  // without the leading slash
  options.frame = "velodyne";         // the cloud's own frame: identity, every cloud placed
  auto source = openDataset(bag, options);
  Scan scan;
  size_t count = 0;
  while (source->next(scan)) {
    EXPECT_TRUE(scan.T_map_sensor.isApprox(Eigen::Isometry3d::Identity()));
    ++count;
  }
  EXPECT_EQ(count, 3u);
  EXPECT_EQ(source->skipped(), 0u);

  options.frame = "base_link";  // static mount only: poses exist at every stamp
  source = openDataset(bag, options);
  count = 0;
  while (source->next(scan)) ++count;
  EXPECT_EQ(count, 3u);

  options.topic = "/points";
  expectIoError([&] { openDataset(bag, options); }, {bag, "no topic /points", "/velodyne_points"});
  options.topic = "/tf";
  expectIoError([&] { openDataset(bag, options); }, {bag, "tf2_msgs/TFMessage"});
}

TEST_F(RosbagTest, SeveralCloudTopicsNeedAChoice) {
  const std::string bag = makeBag(dir_, "two-topics");
  expectIoError([&] { openDataset(bag); },
                {bag, "2 PointCloud2 topics", "/camera/points", "/velodyne_points"});
  DatasetOptions options;
  options.topic = "/camera/points";
  options.frame = "camera";
  auto source = openDataset(bag, options);
  Scan scan;
  ASSERT_TRUE(source->next(scan));
  EXPECT_EQ(scan.cloud.size(), 100u);
  EXPECT_FALSE(source->next(scan));
}

TEST_F(RosbagTest, NoTransformForAnyCloudIsAnError) {
  const std::string bag = makeBag(dir_, "no-tf");
  auto source = openDataset(bag);
  Scan scan;
  expectIoError([&] { source->next(scan); }, {bag, "none of the 3 clouds", "'map'"});
}

TEST_F(RosbagTest, DamagedBags) {
  const std::string bag = makeBag(dir_, "normal");
  const std::string bytes = test::readBytes(bag);
  const std::string damaged = dir_ + "/damaged.bag";
  test::writeBytes(damaged, "not a bag at all\n");
  expectIoError([&] { openDataset(damaged); }, {damaged});
  test::writeBytes(damaged, bytes.substr(0, bytes.size() / 2));  // index lost
  expectIoError(
      [&] {
        auto source = openDataset(damaged);
        Scan scan;
        while (source->next(scan)) {
        }
      },
      {damaged});
  for (size_t cut : {size_t{0}, size_t{13}, size_t{100}, size_t{5000}, bytes.size() - 100}) {
    test::writeBytes(damaged, bytes.substr(0, cut));
    test::expectParsesOrIoError(
        [&] {
          auto source = openDataset(damaged);
          Scan scan;
          while (source->next(scan)) {
          }
        },
        "cut at " + std::to_string(cut));
  }
}

}  // namespace
}  // namespace fragg
