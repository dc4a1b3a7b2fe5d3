// dynamic_reconfigure -> the server's parameters (reconfigure.h).
#include "reconfigure.h"

#include <ros/console.h>

#include <exception>
#include <utility>

namespace fragg::ros {

namespace {
ReconfigurableParams valuesOf(const fragg_map::MapServerConfig& c) {
  ReconfigurableParams v;
  v.compress_map = c.compress_map;
  v.incremental_2D_projection = c.incremental_2D_projection;
  v.filter_speckles = c.filter_speckles;
  v.occupancy_min_z_m = c.occupancy_min_z;
  v.occupancy_max_z_m = c.occupancy_max_z;
  v.sensor_model_max_range_m = c.sensor_model_max_range;
  v.sensor_model_min_range_m = c.sensor_model_min_range;
  v.filter_ground = c.filter_ground;
  v.ground_filter_distance_m = c.ground_filter_distance;
  v.ground_filter_angle_rad = c.ground_filter_angle;
  v.ground_filter_plane_distance_m = c.ground_filter_plane_distance;
  return v;
}

fragg_map::MapServerConfig configOf(const ReconfigurableParams& v) {
  fragg_map::MapServerConfig c = fragg_map::MapServerConfig::__getDefault__();
  c.compress_map = v.compress_map;
  c.incremental_2D_projection = v.incremental_2D_projection;
  c.filter_speckles = v.filter_speckles;
  c.occupancy_min_z = v.occupancy_min_z_m;
  c.occupancy_max_z = v.occupancy_max_z_m;
  c.sensor_model_max_range = v.sensor_model_max_range_m;
  c.sensor_model_min_range = v.sensor_model_min_range_m;
  c.filter_ground = v.filter_ground;
  c.ground_filter_distance = v.ground_filter_distance_m;
  c.ground_filter_angle = v.ground_filter_angle_rad;
  c.ground_filter_plane_distance = v.ground_filter_plane_distance_m;
  return c;
}
}  // namespace

ReconfigureServer::ReconfigureServer(::ros::NodeHandle& private_nh, const ServerParams& current,
                                     ApplyFn apply)
    : params_(current), apply_(std::move(apply)), server_(mutex_, private_nh) {
  // The start-up values (read from the YAML's nested names, sensor_model/max_range...) replace
  // whatever the flat names hold, before the first callback.
  fragg_map::MapServerConfig config = configOf(reconfigurableOf(params_));
  server_.updateConfig(config);
  server_.setCallback(
      [this](fragg_map::MapServerConfig& c, uint32_t level) { onChange(c, level); });
}

void ReconfigureServer::onChange(fragg_map::MapServerConfig& config, uint32_t /*level*/) {
  const ReconfigurableParams before = reconfigurableOf(params_);
  if (!started_) {
    started_ = true;
    config = configOf(before);
    return;
  }
  try {
    ServerParams next = withReconfigured(params_, valuesOf(config));
    apply_(next);
    params_ = std::move(next);
    ROS_INFO("fragg_map: dynamic_reconfigure: parameters applied");
  } catch (const std::exception& e) {
    ROS_WARN("fragg_map: dynamic_reconfigure: change refused, values kept: %s", e.what());
    config = configOf(before);  // the server publishes what it is given back
  }
}

}  // namespace fragg::ros
