// colored_map: cell colours averaged as ColorOcTree::averageNodeColor (c = (c + p) / 2), only
// for the points the insertion makes occupied (range, height band, finite), drawn by the
// occupied markers, redrawn when only the colours change, dropped with the cells.
#include "fragg_map/ros/cell_colors.h"

#include <gtest/gtest.h>
#include <sensor_msgs/PointField.h>

#include <cmath>
#include <cstring>
#include <vector>

#include "fragg_map/errors.h"
#include "fragg_map/ros/block_markers.h"
#include "map_fixtures.h"

namespace fragg::ros {
namespace {

struct ColoredPoint {
  float x, y, z;
  uint32_t rgb;  ///< 0x00RRGGBB
};

/// x y z float32 + rgb (PCL's packing: a FLOAT32 field holding the bytes) at 12, step 16.
sensor_msgs::PointCloud2 coloredCloud(const std::vector<ColoredPoint>& points,
                                      uint8_t rgb_type = sensor_msgs::PointField::FLOAT32) {
  sensor_msgs::PointCloud2 msg;
  msg.header.frame_id = "sensor";
  msg.height = 1;
  msg.width = static_cast<uint32_t>(points.size());
  const char* names[4] = {"x", "y", "z", "rgb"};
  for (uint32_t i = 0; i < 4; ++i) {
    sensor_msgs::PointField f;
    f.name = names[i];
    f.offset = 4 * i;
    f.datatype = i < 3 ? uint8_t{sensor_msgs::PointField::FLOAT32} : rgb_type;
    f.count = 1;
    msg.fields.push_back(f);
  }
  msg.point_step = 16;
  msg.row_step = 16 * msg.width;
  msg.data.resize(msg.row_step);
  for (size_t i = 0; i < points.size(); ++i) std::memcpy(&msg.data[16 * i], &points[i], 16);
  return msg;
}

fragg::PointCloud xyzOf(const std::vector<ColoredPoint>& points) {
  fragg::PointCloud cloud;
  for (const ColoredPoint& p : points) cloud.points_S.emplace_back(p.x, p.y, p.z);
  return cloud;
}

TEST(CellColors, AveragedAsColorOcTreeWithinRangeAndBand) {
  fragg::MapParams params = test::cpuParams(0.1);
  params.height_filter.max_z_m = 1.0;
  fragg::Map map(params);
  CellColors colors;
  const Eigen::Isometry3d T_map_sensor = Eigen::Isometry3d::Identity();
  // Three points in the cell of (2.03, 0.05, 0.05), one beyond 3 m, one above the band, a NaN.
  const std::vector<ColoredPoint> points = {
      {2.03f, 0.05f, 0.05f, 0xff0000}, {2.04f, 0.06f, 0.04f, 0x00ff00},
      {2.06f, 0.02f, 0.07f, 0x0000fe}, {4.05f, 0.05f, 0.05f, 0x123456},
      {2.05f, 0.05f, 1.55f, 0x654321}, {std::nanf(""), 0.0f, 0.0f, 0xffffff},
      {2.05f, 0.55f, 0.05f, 0x102030}};
  EXPECT_EQ(colors.integrate(coloredCloud(points), T_map_sensor, 3.0, map), 4u);
  const fragg::VoxelKey cell = map.keyOf(Eigen::Vector3d(2.05, 0.05, 0.05));
  const std::optional<Rgb8> c = colors.find(cell);
  ASSERT_TRUE(c);
  // ((255 + 0) / 2 + 0) / 2 = 63; (0 + 255) / 2 / 2 = 63; (0 + 254) / 2 = 127.
  EXPECT_EQ(int{c->r}, 63);
  EXPECT_EQ(int{c->g}, 63);
  EXPECT_EQ(int{c->b}, 127);
  EXPECT_FALSE(colors.find(map.keyOf(Eigen::Vector3d(4.05, 0.05, 0.05))));  // beyond range
  EXPECT_FALSE(colors.find(map.keyOf(Eigen::Vector3d(2.05, 0.05, 1.55))));  // above the band
  const std::optional<Rgb8> other = colors.find(map.keyOf(Eigen::Vector3d(2.05, 0.55, 0.05)));
  ASSERT_TRUE(other);
  EXPECT_TRUE((*other == Rgb8{0x10, 0x20, 0x30}));
  EXPECT_EQ(colors.cells(), 2u);
  // No rgb field: nothing; a one-byte rgb field: refused.
  sensor_msgs::PointCloud2 plain = coloredCloud(points);
  plain.fields.pop_back();
  EXPECT_FALSE(hasRgbField(plain));
  EXPECT_EQ(colors.integrate(plain, T_map_sensor, 3.0, map), 0u);
  EXPECT_THROW(colors.integrate(coloredCloud(points, sensor_msgs::PointField::UINT8), T_map_sensor,
                                3.0, map),
               fragg::InvalidArgument);
}

TEST(CellColors, MarkersDrawTheColoursAndRedrawOnRecolouring) {
  fragg::Map map(test::cpuParams(0.1));
  CellColors colors;
  MarkerStyle style;
  style.height_colors = false;  // flat blue where a cell has no colour
  style.colors = &colors;
  const Eigen::Isometry3d T_map_sensor = Eigen::Isometry3d::Identity();
  std::vector<ColoredPoint> points;
  for (int i = 0; i < 5; ++i) points.push_back({2.05f, 0.05f + 0.1f * i, 0.05f, 0xc08040});
  const fragg::SensorModel sensor = fragg::SensorModel::autoFromCloud(0.0, -1.0);
  for (int n = 0; n < 3; ++n) map.insert(xyzOf(points), T_map_sensor, sensor);
  test::setCell(map, map.keyOf(Eigen::Vector3d(2.05, -0.05, 0.05)), fragg::CellState::kOccupied);
  colors.integrate(coloredCloud(points), T_map_sensor, -1.0, map);
  MarkerLedger ledger;
  const visualization_msgs::MarkerArray all = allBlockMarkers(map, style, ::ros::Time(), &ledger);
  size_t coloured = 0, flat = 0;
  for (const visualization_msgs::Marker& m : all.markers) {
    for (size_t i = 0; i < m.points.size(); ++i) {
      const std_msgs::ColorRGBA& c = m.colors[i];
      if (m.points[i].y < 0.0) {
        EXPECT_FLOAT_EQ(c.b, 1.0f);  // the written cell: no colour
        EXPECT_FLOAT_EQ(c.r, 0.0f);
        ++flat;
      } else {
        EXPECT_FLOAT_EQ(c.r, 0xc0 / 255.0f);
        EXPECT_FLOAT_EQ(c.g, 0x80 / 255.0f);
        EXPECT_FLOAT_EQ(c.b, 0x40 / 255.0f);
        ++coloured;
      }
    }
  }
  EXPECT_EQ(coloured, 5u);
  EXPECT_EQ(flat, 1u);
  // The same cells again (still occupied: no occupancy change), in another colour.
  for (ColoredPoint& p : points) p.rgb = 0x000000;
  map.insert(xyzOf(points), T_map_sensor, sensor);
  EXPECT_TRUE(
      map.changedBlocksSince(ledger.publishedRevision(), fragg::BlockChange::kOccupied).empty());
  colors.integrate(coloredCloud(points), T_map_sensor, -1.0, map);
  const visualization_msgs::MarkerArray changed =
      changedBlockMarkers(map, style, ::ros::Time(), &ledger);
  size_t redrawn = 0;
  for (const visualization_msgs::Marker& m : changed.markers)
    for (size_t i = 0; i < m.points.size(); ++i)
      if (m.points[i].y > 0.0) {
        EXPECT_FLOAT_EQ(m.colors[i].r, 0x60 / 255.0f);  // (0xc0 + 0) / 2
        ++redrawn;
      }
  EXPECT_EQ(redrawn, 5u);
  // Nothing new: nothing redrawn.
  EXPECT_TRUE(changedBlockMarkers(map, style, ::ros::Time(), &ledger).markers.empty());
  // Cleared cells lose their colours.
  map.clearBox(Eigen::Vector3d(1.9, 0.0, -1.0), Eigen::Vector3d(2.2, 0.25, 1.0));
  colors.prune(map);
  EXPECT_FALSE(colors.find(map.keyOf(Eigen::Vector3d(2.05, 0.05, 0.05))));
  EXPECT_TRUE(colors.find(map.keyOf(Eigen::Vector3d(2.05, 0.35, 0.05))));
  map.reset();
  colors.prune(map);
  EXPECT_EQ(colors.cells(), 0u);
}

}  // namespace
}  // namespace fragg::ros
