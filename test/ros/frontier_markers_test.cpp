// The frontier topics' messages: one CUBE_LIST per cluster with its cell centres, arrows at
// the viewpoints along their yaw coloured by gain, DELETEALL first, the even subsample beyond
// max_cells (markers and cloud), bad input refused.
#include "fragg_map/ros/frontier_markers.h"

#include <gtest/gtest.h>
#include <sensor_msgs/point_cloud2_iterator.h>

#include <cmath>
#include <vector>

#include "fragg_map/errors.h"

namespace {

using fragg::VoxelKey;
using fragg::planning::FrontierCluster;
using fragg::planning::Viewpoint;
using visualization_msgs::Marker;

FrontierCluster cluster(uint64_t id, int x0, int n) {
  FrontierCluster c;
  c.id = id;
  for (int i = 0; i < n; ++i) c.cells.push_back(VoxelKey{x0 + i, -1, 2});
  return c;
}

Viewpoint view(double x, double yaw, double gain) {
  Viewpoint v;
  v.position_m = Eigen::Vector3d(x, 1.0, 0.5);
  v.yaw_rad = yaw;
  v.gain_bits = gain;
  return v;
}

TEST(FrontierMarkers, SubsampleStride) {
  EXPECT_EQ(fragg::ros::subsampleStride(0, 0), 1u);
  EXPECT_EQ(fragg::ros::subsampleStride(10, 10), 1u);
  EXPECT_EQ(fragg::ros::subsampleStride(11, 10), 2u);
  EXPECT_EQ(fragg::ros::subsampleStride(30, 10), 3u);
  EXPECT_EQ(fragg::ros::subsampleStride(31, 10), 4u);
  EXPECT_EQ(fragg::ros::subsampleStride(5, 0), 0u);
}

TEST(FrontierMarkers, CubesPerClusterAndArrowsByGain) {
  const std::vector<FrontierCluster> clusters = {cluster(4, 0, 3), cluster(9, 10, 5)};
  const std::vector<std::vector<Viewpoint>> views = {
      {view(0.0, 0.0, 100.0)}, {view(1.0, M_PI / 2, 20.0), view(2.0, -M_PI / 2, 60.0)}};
  fragg::ros::FrontierMarkerInput in;
  in.clusters = &clusters;
  in.views = &views;
  in.resolution_m = 0.1;
  uint64_t drawn = 0;
  const auto a = fragg::ros::frontierMarkers(in, "map", ros::Time(3.0), 1000, &drawn);
  EXPECT_EQ(drawn, 8u);
  ASSERT_EQ(a.markers.size(), 1u + 2u + 3u);
  EXPECT_EQ(a.markers[0].action, Marker::DELETEALL);
  for (int i = 1; i <= 2; ++i) {
    const Marker& m = a.markers[i];
    EXPECT_EQ(m.ns, "frontier_cells");
    EXPECT_EQ(m.type, Marker::CUBE_LIST);
    EXPECT_EQ(m.header.frame_id, "map");
    EXPECT_EQ(m.scale.x, 0.1);
    const FrontierCluster& c = clusters[i - 1];
    EXPECT_EQ(m.id, static_cast<int>(c.id));
    ASSERT_EQ(m.points.size(), c.cells.size());
    for (size_t k = 0; k < c.cells.size(); ++k) {
      EXPECT_NEAR(m.points[k].x, (c.cells[k].x + 0.5) * 0.1, 1e-12);
      EXPECT_NEAR(m.points[k].y, -0.05, 1e-12);
      EXPECT_NEAR(m.points[k].z, 0.25, 1e-12);
    }
  }
  EXPECT_NE(a.markers[1].color, a.markers[2].color) << "clusters in different colours";
  EXPECT_EQ(a.markers[1].color, fragg::ros::clusterColor(4));
  // Arrows: position, yaw as a quaternion, green for the highest gain, red for the lowest.
  const Marker& best = a.markers[3];
  EXPECT_EQ(best.ns, "viewpoints");
  EXPECT_EQ(best.type, Marker::ARROW);
  EXPECT_EQ(best.pose.position.x, 0.0);
  EXPECT_NEAR(best.pose.orientation.w, 1.0, 1e-12);
  EXPECT_FLOAT_EQ(best.color.g, 1.0f);
  EXPECT_FLOAT_EQ(best.color.r, 0.0f);
  const Marker& low = a.markers[4];
  EXPECT_NEAR(2.0 * std::atan2(low.pose.orientation.z, low.pose.orientation.w), M_PI / 2, 1e-12);
  EXPECT_FLOAT_EQ(low.color.r, 1.0f);
  EXPECT_FLOAT_EQ(low.color.g, 0.0f);
  EXPECT_NE(a.markers[3].id, a.markers[5].id);
}

TEST(FrontierMarkers, CapKeepsAnEvenSubsample) {
  const std::vector<FrontierCluster> clusters = {cluster(1, 0, 7), cluster(2, 20, 7)};
  fragg::ros::FrontierMarkerInput in;
  in.clusters = &clusters;
  in.resolution_m = 0.05;
  uint64_t drawn = 0;
  auto a = fragg::ros::frontierMarkers(in, "map", ros::Time(), 5, &drawn);
  EXPECT_EQ(drawn, 5u) << "every third of 14 cells";
  size_t points = 0;
  for (const Marker& m : a.markers) points += m.points.size();
  EXPECT_EQ(points, 5u);
  a = fragg::ros::frontierMarkers(in, "map", ros::Time(), 0, &drawn);
  EXPECT_EQ(drawn, 0u);
  EXPECT_EQ(a.markers.size(), 1u) << "only the DELETEALL";

  std::vector<VoxelKey> cells;
  for (int i = 0; i < 25; ++i) cells.push_back(VoxelKey{i, 0, -1});
  const auto cloud = fragg::ros::frontierCloud(cells, 0.05, "map", ros::Time(1.0), 10);
  EXPECT_EQ(cloud.width, 9u) << "every third of 25";
  EXPECT_EQ(cloud.height, 1u);
  sensor_msgs::PointCloud2ConstIterator<float> x(cloud, "x"), z(cloud, "z");
  for (int i = 0; i < 9; ++i, ++x, ++z) {
    EXPECT_FLOAT_EQ(*x, static_cast<float>((3 * i + 0.5) * 0.05));
    EXPECT_FLOAT_EQ(*z, static_cast<float>(-0.5 * 0.05));
  }
  EXPECT_EQ(fragg::ros::frontierCloud(cells, 0.05, "map", ros::Time(), 100).width, 25u);
}

TEST(FrontierMarkers, BadInputRefused) {
  const std::vector<FrontierCluster> clusters = {cluster(1, 0, 2)};
  const std::vector<std::vector<Viewpoint>> views(2);
  fragg::ros::FrontierMarkerInput in;
  in.clusters = &clusters;
  in.views = &views;
  in.resolution_m = 0.1;
  EXPECT_THROW(fragg::ros::frontierMarkers(in, "map", ros::Time(), 10), fragg::InvalidArgument);
  in.views = nullptr;
  in.resolution_m = 0.0;
  EXPECT_THROW(fragg::ros::frontierMarkers(in, "map", ros::Time(), 10), fragg::InvalidArgument);
}

}  // namespace
