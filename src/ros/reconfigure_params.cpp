// dynamic_reconfigure's values <-> the server's parameters (reconfigure_params.h).
#include "fragg_map/ros/reconfigure_params.h"

#include <cmath>
#include <limits>

#include "fragg_map/errors.h"

namespace fragg::ros {

namespace {
constexpr double kInf = std::numeric_limits<double>::infinity();

double heightToCfg(double z_m) {
  return std::max(-kReconfigureNoHeightLimitM, std::min(kReconfigureNoHeightLimitM, z_m));
}
double heightFromCfg(double z_m) {
  if (z_m <= -kReconfigureNoHeightLimitM) return -kInf;
  if (z_m >= kReconfigureNoHeightLimitM) return kInf;
  return z_m;
}
void bad(const std::string& name, const std::string& why) {
  throw fragg::InvalidArgument("parameter '" + name + "' " + why);
}
}  // namespace

ReconfigurableParams reconfigurableOf(const ServerParams& p) {
  ReconfigurableParams v;
  v.compress_map = p.octomap.compress_map;
  v.incremental_2D_projection = p.octomap.incremental_2D_projection;
  v.filter_speckles = p.octomap.filter_speckles;
  v.occupancy_min_z_m = heightToCfg(p.occupancy_min_z_m);
  v.occupancy_max_z_m = heightToCfg(p.occupancy_max_z_m);
  v.sensor_model_max_range_m = p.sensor.max_range_m;
  v.sensor_model_min_range_m = p.sensor.min_range_m;
  v.filter_ground = p.octomap.filter_ground;
  v.ground_filter_distance_m = p.octomap.ground_distance_m;
  v.ground_filter_angle_rad = p.octomap.ground_angle_rad;
  v.ground_filter_plane_distance_m = p.octomap.ground_plane_distance_m;
  return v;
}

ServerParams withReconfigured(const ServerParams& p, const ReconfigurableParams& v) {
  ServerParams out = p;
  out.octomap.compress_map = v.compress_map;
  out.octomap.incremental_2D_projection = v.incremental_2D_projection;
  out.octomap.filter_speckles = v.filter_speckles;
  // A height of the cfg's range end keeps a finite start-up value beyond it unchanged.
  const double min_z = heightFromCfg(v.occupancy_min_z_m),
               max_z = heightFromCfg(v.occupancy_max_z_m);
  if (std::isnan(min_z) || std::isnan(max_z)) bad("occupancy_min_z/max_z", "must be numbers");
  if (min_z > max_z) bad("occupancy_min_z", "must not lie above occupancy_max_z");
  if (heightToCfg(p.occupancy_min_z_m) != v.occupancy_min_z_m) out.occupancy_min_z_m = min_z;
  if (heightToCfg(p.occupancy_max_z_m) != v.occupancy_max_z_m) out.occupancy_max_z_m = max_z;
  out.sensor.max_range_m = v.sensor_model_max_range_m;
  out.sensor.min_range_m = std::max(0.0, v.sensor_model_min_range_m);
  try {
    out.sensor.validate();
  } catch (const fragg::InvalidArgument& e) {
    bad("sensor_model_max_range/min_range", std::string("gives a bad sensor model: ") + e.what());
  }
  if (!(v.ground_filter_distance_m > 0.0) || !std::isfinite(v.ground_filter_distance_m))
    bad("ground_filter_distance", "must be a finite distance in metres > 0");
  if (!(v.ground_filter_angle_rad >= 0.0 && v.ground_filter_angle_rad <= M_PI / 2))
    bad("ground_filter_angle", "must be in [0, pi/2] rad");
  if (!(v.ground_filter_plane_distance_m >= 0.0) ||
      !std::isfinite(v.ground_filter_plane_distance_m))
    bad("ground_filter_plane_distance", "must be a finite distance in metres >= 0");
  out.octomap.filter_ground = v.filter_ground;
  out.octomap.ground_distance_m = v.ground_filter_distance_m;
  out.octomap.ground_angle_rad = v.ground_filter_angle_rad;
  out.octomap.ground_plane_distance_m = v.ground_filter_plane_distance_m;
  return out;
}

}  // namespace fragg::ros
