// Flags, checks and the computation shared by `fragg_map frontiers` and `render --frontiers`.
#include "cli/frontier_options.h"

#include <fmt/format.h>

#include <algorithm>
#include <chrono>
#include <cmath>

#include "fragg_map/errors.h"

namespace fragg::cli {

namespace {

constexpr double kDegToRad = 3.14159265358979323846 / 180.0;

planning::GainSensor sensorFrom(const FrontierFlags& o) {
  planning::GainSensor s;
  if (o.sensor == "lidar") {
    s.kind = planning::GainSensor::Kind::kLidar;
    s.columns = 360;
    s.rows = 16;
  } else if (o.sensor != "pinhole") {
    throw InvalidArgument(fmt::format("--sensor must be pinhole or lidar, got '{}'", o.sensor));
  }
  if (!o.rays.empty()) {
    for (double r : o.rays)
      if (!(r >= 1.0) || r != std::floor(r) || r > 1e6)
        throw InvalidArgument(fmt::format("--rays takes two whole numbers >= 1, got {}", r));
    s.columns = static_cast<int>(o.rays[0]);
    s.rows = static_cast<int>(o.rays[1]);
  }
  if (!o.fov_deg.empty()) {
    s.horizontal_fov_rad = o.fov_deg[0] * kDegToRad;
    s.vertical_fov_rad = o.fov_deg[1] * kDegToRad;
  }
  if (!o.elevation_deg.empty()) {
    s.min_elevation_rad = o.elevation_deg[0] * kDegToRad;
    s.max_elevation_rad = o.elevation_deg[1] * kDegToRad;
  }
  s.max_range_m = o.max_range_m;
  s.validate();
  return s;
}

}  // namespace

void addFrontierFlags(CLI::App* c, FrontierFlags* o, CLI::Option* needs) {
  std::vector<CLI::Option*> added;
  const auto add = [&](CLI::Option* opt) {
    added.push_back(opt);
    return opt;
  };
  add(c->add_option("--box", o->box, "Keep frontier cells with centres in X0 Y0 Z0 X1 Y1 Z1 (m)")
          ->expected(6));
  add(c->add_option("--height", o->height, "Keep frontier cells with centre z in MIN MAX (m)")
          ->expected(2));
  add(c->add_option("--min-obstacle-distance", o->min_obstacle_distance_m,
                    "Drop frontier cells closer than M metres to an occupied cell (0: off)")
          ->capture_default_str());
  add(c->add_option("--min-cluster", o->min_cluster, "Drop clusters of fewer cells")
          ->capture_default_str());
  add(c->add_option("--max-extent", o->max_extent_m,
                    "Split clusters wider than M metres along their principal axis (0: never)")
          ->capture_default_str());
  add(c->add_option("--viewpoints", o->viewpoints, "Best K viewpoints per cluster (0: none)")
          ->capture_default_str());
  add(c->add_option("--gain", o->gain,
                    "Viewpoint gain: entropy (bits of the unknown cells the rays cross) | "
                    "coverage (the cluster's frontier cells in view, FUEL's rule; fast on "
                    "large maps)")
          ->capture_default_str());
  add(c->add_option("--sensor", o->sensor, "Gain sensor: pinhole | lidar")->capture_default_str());
  add(c->add_option("--rays", o->rays,
                    "Rays COLUMNS ROWS (pinhole default 64 48, lidar 360 azimuths x 16 beams)")
          ->expected(2));
  add(c->add_option("--fov", o->fov_deg, "Pinhole field of view H V in degrees (default 90 68.8)")
          ->expected(2));
  add(c->add_option("--elevation", o->elevation_deg, "LiDAR elevations MIN MAX, degrees (-15 15)")
          ->expected(2));
  add(c->add_option("--max-range", o->max_range_m, "Gain sensor range (m)")->capture_default_str());
  add(c->add_option("--radii", o->radii, "Viewpoint ring radii around each cluster (m)")
          ->capture_default_str());
  add(c->add_option("--heights", o->heights, "Viewpoint heights relative to the centroid (m)")
          ->capture_default_str());
  add(c->add_option("--angles", o->angles, "Viewpoints per ring")->capture_default_str());
  add(c->add_option("--clearance", o->clearance_m,
                    "Free radius a viewpoint needs (no occupied or unknown cell), metres")
          ->capture_default_str());
  add(c->add_option("--robot", o->robot, "Rank viewpoints by gain per metre from X Y Z")
          ->expected(3));
  add(c->add_option("--threads", o->threads, "CPU threads (0 = every core)")
          ->capture_default_str());
  if (needs)
    for (CLI::Option* opt : added) opt->needs(needs);
}

FrontierSettings frontierSettings(const FrontierFlags& o) {
  FrontierSettings s;
  planning::FrontierFilter& filter = s.filter;
  if (!o.box.empty()) {
    filter.use_box = true;
    filter.box_min_m = Eigen::Vector3d(o.box[0], o.box[1], o.box[2]);
    filter.box_max_m = Eigen::Vector3d(o.box[3], o.box[4], o.box[5]);
  }
  if (!o.height.empty()) {
    filter.use_height = true;
    filter.min_z_m = o.height[0];
    filter.max_z_m = o.height[1];
  }
  filter.min_obstacle_distance_m = o.min_obstacle_distance_m;
  filter.validate();
  s.clusters.min_cells = o.min_cluster;
  s.clusters.max_extent_m = o.max_extent_m;
  s.clusters.validate();
  if (o.viewpoints < 0)
    throw InvalidArgument(fmt::format("--viewpoints must be >= 0, got {}", o.viewpoints));
  s.viewpoints = o.viewpoints;
  planning::ViewpointOptions& views = s.views;
  views.radii_m = o.radii;
  views.heights_m = o.heights;
  views.angles = o.angles;
  views.clearance_m = o.clearance_m;
  views.top_k = std::max(o.viewpoints, 1);
  views.sensor = sensorFrom(o);
  views.gain = planning::viewpointGainFromName(o.gain);
  if (!o.robot.empty()) views.robot_m = Eigen::Vector3d(o.robot[0], o.robot[1], o.robot[2]);
  views.validate();
  if (o.threads < 0)
    throw InvalidArgument(fmt::format("--threads must be >= 0, got {}", o.threads));
  s.threads = o.threads;
  return s;
}

FrontierResult computeFrontiers(const Map& map, const FrontierSettings& s) {
  FrontierResult r;
  const auto t0 = std::chrono::steady_clock::now();
  r.cells = planning::findFrontierCells(map, s.filter, s.threads);
  const auto t1 = std::chrono::steady_clock::now();
  planning::FrontierClusterer clusterer(s.clusters);
  r.clusters = clusterer.cluster(map, r.cells);
  r.views.resize(r.clusters.size());
  if (s.viewpoints > 0) r.views = planning::clustersViewpoints(map, r.clusters, s.views, s.threads);
  const auto t2 = std::chrono::steady_clock::now();
  r.cells_ms = std::chrono::duration<double, std::milli>(t1 - t0).count();
  r.clusters_viewpoints_ms = std::chrono::duration<double, std::milli>(t2 - t1).count();
  return r;
}

}  // namespace fragg::cli
