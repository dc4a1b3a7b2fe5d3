// PointCloud2 -> fragg::PointCloud: both conversion paths, organised clouds, and every kind of
// malformed message.
#include "fragg_map/ros/cloud_from_msg.h"

#include <gtest/gtest.h>

#include <cmath>
#include <limits>
#include <random>

#include "cloud_msg_builder.h"
#include "fragg_map/errors.h"

namespace {

using fragg::ros::cloudFromMsg;
using fragg::ros::CloudLayout;
using fragg::ros::test::FieldSpec;
using fragg::ros::test::makeCloud;
using fragg::ros::test::packedXyz;
using F = sensor_msgs::PointField;

std::vector<Eigen::Vector3f> randomPoints(size_t n, unsigned seed = 7) {
  std::mt19937 rng(seed);
  std::uniform_real_distribution<float> d(-40.f, 40.f);
  std::vector<Eigen::Vector3f> pts(n);
  for (auto& p : pts) p = {d(rng), d(rng), d(rng)};
  return pts;
}

void expectSamePoints(const std::vector<Eigen::Vector3f>& want, const fragg::PointCloud& got) {
  ASSERT_EQ(want.size(), got.size());
  for (size_t i = 0; i < want.size(); ++i) {
    if (!want[i].allFinite()) {
      EXPECT_FALSE(got.points_S[i].allFinite()) << "point " << i;
      continue;
    }
    EXPECT_EQ(want[i], got.points_S[i]) << "point " << i;
  }
}

// Expects cloudFromMsg to throw InvalidArgument mentioning `phrase`.
void expectRejected(const sensor_msgs::PointCloud2& msg, const std::string& phrase) {
  try {
    cloudFromMsg(msg);
    FAIL() << "accepted a cloud that should fail with '" << phrase << "'";
  } catch (const fragg::InvalidArgument& e) {
    EXPECT_NE(std::string(e.what()).find(phrase), std::string::npos) << e.what();
  }
}

TEST(CloudFromMsg, PackedXyzIsCopiedExactly) {
  const auto pts = randomPoints(1000);
  CloudLayout layout{};
  const fragg::PointCloud cloud = cloudFromMsg(makeCloud(pts, 1000, 1, packedXyz(), 12), &layout);
  EXPECT_EQ(layout, CloudLayout::kPackedFloat32);
  expectSamePoints(pts, cloud);
  EXPECT_FALSE(cloud.organised());
}

TEST(CloudFromMsg, PackedXyzWithIntensityAndRowPadding) {
  // Velodyne-like: x y z at 0 4 8, intensity at 12, ring at 16, point_step 32; padded rows.
  auto fields = packedXyz();
  fields.push_back({"intensity", 12, F::FLOAT32});
  fields.push_back({"ring", 16, F::UINT16});
  const auto pts = randomPoints(64 * 3);
  CloudLayout layout{};
  const fragg::PointCloud cloud = cloudFromMsg(makeCloud(pts, 64, 3, fields, 32, 8), &layout);
  EXPECT_EQ(layout, CloudLayout::kPackedFloat32);
  expectSamePoints(pts, cloud);
  EXPECT_TRUE(cloud.organised());
  EXPECT_EQ(cloud.width, 64u);
  EXPECT_EQ(cloud.height, 3u);
}

TEST(CloudFromMsg, ShuffledFloat32FieldsGoThroughTheStridedPath) {
  const std::vector<FieldSpec> fields = {{"intensity", 0, F::FLOAT32},
                                         {"z", 4, F::FLOAT32},
                                         {"x", 8, F::FLOAT32},
                                         {"y", 12, F::FLOAT32}};
  const auto pts = randomPoints(500);
  CloudLayout layout{};
  const fragg::PointCloud cloud = cloudFromMsg(makeCloud(pts, 500, 1, fields, 16), &layout);
  EXPECT_EQ(layout, CloudLayout::kStrided);
  expectSamePoints(pts, cloud);
}

TEST(CloudFromMsg, Float64Fields) {
  const std::vector<FieldSpec> fields = {
      {"x", 0, F::FLOAT64}, {"y", 8, F::FLOAT64}, {"z", 16, F::FLOAT64}};
  const auto pts = randomPoints(300);
  CloudLayout layout{};
  const fragg::PointCloud cloud = cloudFromMsg(makeCloud(pts, 300, 1, fields, 24), &layout);
  EXPECT_EQ(layout, CloudLayout::kStrided);
  expectSamePoints(pts, cloud);  // float -> double -> float is exact
}

TEST(CloudFromMsg, BigEndianFloat32) {
  auto pts = randomPoints(50);
  sensor_msgs::PointCloud2 msg = makeCloud(pts, 50, 1, packedXyz(), 12);
  for (size_t i = 0; i < msg.data.size(); i += 4) std::reverse(&msg.data[i], &msg.data[i + 4]);
  msg.is_bigendian = true;
  CloudLayout layout{};
  const fragg::PointCloud cloud = cloudFromMsg(msg, &layout);
  EXPECT_EQ(layout, CloudLayout::kStrided);
  expectSamePoints(pts, cloud);
}

TEST(CloudFromMsg, OrganisedDepthCloudKeepsItsNaNsInPlace) {
  const float nan = std::numeric_limits<float>::quiet_NaN();
  auto pts = randomPoints(8 * 6);
  pts[0] = {nan, nan, nan};
  pts[13] = {nan, nan, nan};
  pts[47] = {nan, nan, nan};
  const fragg::PointCloud cloud = cloudFromMsg(makeCloud(pts, 8, 6, packedXyz(), 16));
  EXPECT_TRUE(cloud.organised());
  EXPECT_EQ(cloud.width, 8u);
  EXPECT_EQ(cloud.height, 6u);
  expectSamePoints(pts, cloud);
  EXPECT_EQ(fragg::ros::finitePointCount(cloud), 45u);
}

// Converting into a kept cloud (the server's insertion thread keeps the last cloud's point
// buffer): every field is the new message's (an organised cloud after an unorganised one, a
// flag list dropped), and a buffer large enough is written in place, not replaced.
TEST(CloudFromMsg, IntoAKeptCloudEveryFieldIsNewAndItsBufferIsReused) {
  const float nan = std::numeric_limits<float>::quiet_NaN();
  fragg::PointCloud kept = cloudFromMsg(makeCloud(randomPoints(1000, 1), 1000, 1, packedXyz(), 12));
  kept.free_only.assign(kept.size(), 1);
  const Eigen::Vector3f* buffer = kept.points_S.data();
  auto organised = randomPoints(8 * 6, 2);
  organised[5] = {nan, nan, nan};
  CloudLayout layout{};
  cloudFromMsg(makeCloud(organised, 8, 6, packedXyz(), 16), &kept, &layout);
  EXPECT_EQ(layout, CloudLayout::kPackedFloat32);
  expectSamePoints(organised, kept);
  EXPECT_TRUE(kept.organised());
  EXPECT_EQ(kept.width, 8u);
  EXPECT_EQ(kept.height, 6u);
  EXPECT_FALSE(kept.hasFreeOnly()) << "the last cloud's flags stayed";
  EXPECT_EQ(kept.points_S.data(), buffer) << "a buffer large enough was replaced";
  // And back to an unorganised cloud through the strided path, in the same buffer.
  const std::vector<FieldSpec> fields = {
      {"z", 0, F::FLOAT32}, {"x", 4, F::FLOAT32}, {"y", 8, F::FLOAT32}};
  const auto pts = randomPoints(900, 3);
  cloudFromMsg(makeCloud(pts, 900, 1, fields, 12), &kept, &layout);
  EXPECT_EQ(layout, CloudLayout::kStrided);
  expectSamePoints(pts, kept);
  EXPECT_FALSE(kept.organised());
  EXPECT_EQ(kept.width, 0u);
  EXPECT_EQ(kept.points_S.data(), buffer);
}

TEST(CloudFromMsg, RejectsMissingField) {
  const auto pts = randomPoints(10);
  expectRejected(makeCloud(pts, 10, 1, {{"x", 0, F::FLOAT32}, {"y", 4, F::FLOAT32}}, 12),
                 "no 'z' field");
  expectRejected(makeCloud(pts, 10, 1, {{"y", 4, F::FLOAT32}, {"z", 8, F::FLOAT32}}, 12),
                 "no 'x' field");
}

TEST(CloudFromMsg, RejectsInt16Fields) {
  const std::vector<FieldSpec> fields = {
      {"x", 0, F::INT16}, {"y", 2, F::INT16}, {"z", 4, F::INT16}};
  expectRejected(makeCloud(randomPoints(10), 10, 1, fields, 6), "datatype 3");
}

TEST(CloudFromMsg, RejectsPointStepSmallerThanTheFields) {
  sensor_msgs::PointCloud2 msg = makeCloud(randomPoints(10), 10, 1, packedXyz(), 12);
  msg.point_step = 8;
  msg.row_step = 80;
  expectRejected(msg, "past point_step 8");
}

TEST(CloudFromMsg, RejectsRowStepSmallerThanARow) {
  sensor_msgs::PointCloud2 msg = makeCloud(randomPoints(20), 10, 2, packedXyz(), 12);
  msg.row_step = 100;
  expectRejected(msg, "row_step 100");
}

TEST(CloudFromMsg, RejectsShortData) {
  sensor_msgs::PointCloud2 msg = makeCloud(randomPoints(10), 10, 1, packedXyz(), 12);
  msg.data.resize(119);
  expectRejected(msg, "data has 119 bytes, 120 needed");
  msg.width = 11;  // declares more points than the data holds
  msg.row_step = 132;
  msg.data.resize(120);
  expectRejected(msg, "data has 120 bytes, 132 needed");
}

TEST(CloudFromMsg, RejectsZeroPoints) {
  expectRejected(makeCloud({}, 0, 1, packedXyz(), 12), "0 points");
  expectRejected(makeCloud({}, 5, 0, packedXyz(), 12), "0 points");
}

TEST(CloudFromMsg, RejectsAllNaN) {
  const float nan = std::numeric_limits<float>::quiet_NaN();
  std::vector<Eigen::Vector3f> pts(12, Eigen::Vector3f(nan, 1.f, nan));
  expectRejected(makeCloud(pts, 4, 3, packedXyz(), 12), "no finite point among 12");
}

}  // namespace
