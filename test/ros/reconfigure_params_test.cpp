// dynamic_reconfigure's values against the server's parameters (reconfigure_params.h): the
// start-up values go out and come back unchanged, a change lands in the field the node reads,
// bad values are refused naming the parameter.
#include "fragg_map/ros/reconfigure_params.h"

#include <gtest/gtest.h>

#include <cmath>
#include <limits>

#include "fragg_map/errors.h"

namespace fragg::ros {
namespace {

constexpr double kInf = std::numeric_limits<double>::infinity();

TEST(ReconfigureParamsTest, StartUpValuesComeBackUnchanged) {
  ServerParams p;
  p.occupancy_min_z_m = -kInf;
  p.occupancy_max_z_m = 2500.0;  // beyond the cfg's range: kept as it is
  p.sensor.max_range_m = 30.0;
  p.octomap.filter_speckles = true;
  const ReconfigurableParams v = reconfigurableOf(p);
  EXPECT_EQ(v.occupancy_min_z_m, -kReconfigureNoHeightLimitM);
  EXPECT_EQ(v.occupancy_max_z_m, kReconfigureNoHeightLimitM);
  const ServerParams back = withReconfigured(p, v);
  EXPECT_EQ(back.occupancy_min_z_m, -kInf);
  EXPECT_EQ(back.occupancy_max_z_m, 2500.0);
  EXPECT_EQ(back.sensor.max_range_m, 30.0);
  EXPECT_TRUE(back.octomap.filter_speckles);
  EXPECT_EQ(back.octomap.compress_map, p.octomap.compress_map);
}

TEST(ReconfigureParamsTest, ChangesLandInTheFieldsTheNodeReads) {
  ServerParams p;
  ReconfigurableParams v = reconfigurableOf(p);
  v.compress_map = !p.octomap.compress_map;
  v.occupancy_min_z_m = -0.5;
  v.occupancy_max_z_m = kReconfigureNoHeightLimitM + 1.0;
  v.sensor_model_max_range_m = 12.5;
  v.sensor_model_min_range_m = -1.0;  // octomap_server's "none"
  v.filter_ground = true;
  v.ground_filter_angle_rad = 0.3;
  const ServerParams q = withReconfigured(p, v);
  EXPECT_EQ(q.octomap.compress_map, !p.octomap.compress_map);
  EXPECT_EQ(q.occupancy_min_z_m, -0.5);
  EXPECT_EQ(q.occupancy_max_z_m, kInf);
  EXPECT_EQ(q.sensor.max_range_m, 12.5);
  EXPECT_EQ(q.sensor.min_range_m, 0.0);
  EXPECT_TRUE(q.octomap.filter_ground);
  EXPECT_EQ(q.octomap.ground_angle_rad, 0.3);
  EXPECT_EQ(q.map.resolution_m, p.map.resolution_m);  // start-up only: untouched
}

TEST(ReconfigureParamsTest, BadValuesAreRefusedByName) {
  const ServerParams p;
  const auto refused = [&](ReconfigurableParams v, const std::string& name) {
    try {
      (void)withReconfigured(p, v);
      ADD_FAILURE() << "accepted; expected a refusal naming " << name;
    } catch (const fragg::InvalidArgument& e) {
      EXPECT_NE(std::string(e.what()).find(name), std::string::npos) << e.what();
    }
  };
  ReconfigurableParams band = reconfigurableOf(p);
  band.occupancy_min_z_m = 2.0;
  band.occupancy_max_z_m = 1.0;
  refused(band, "occupancy_min_z");
  ReconfigurableParams range = reconfigurableOf(p);
  range.sensor_model_min_range_m = 5.0;
  range.sensor_model_max_range_m = 4.0;
  refused(range, "sensor_model_max_range");
  ReconfigurableParams angle = reconfigurableOf(p);
  angle.ground_filter_angle_rad = 2.0;
  refused(angle, "ground_filter_angle");
  ReconfigurableParams distance = reconfigurableOf(p);
  distance.ground_filter_distance_m = std::nan("");
  refused(distance, "ground_filter_distance");
}

}  // namespace
}  // namespace fragg::ros
