// fragg_map frontiers MAP: frontier cells (free cells with an unknown 26-neighbour), their
// clusters and each cluster's best viewpoints by information gain.
#include <fmt/format.h>

#include <chrono>
#include <cmath>
#include <cstdio>
#include <nlohmann/json.hpp>
#include <string>
#include <vector>

#include "cli/commands.h"
#include "cli/map_input.h"
#include "fragg_map/errors.h"
#include "fragg_map/planning/frontier_cells.h"
#include "fragg_map/planning/frontier_clusters.h"
#include "fragg_map/planning/viewpoints.h"

namespace fragg::cli {

namespace {

constexpr double kDegToRad = 3.14159265358979323846 / 180.0;

struct FrontierCommandOptions {
  std::string map, sensor = "pinhole";
  std::vector<double> box, height, robot, rays, fov_deg, elevation_deg;
  std::vector<double> radii = {1.5, 3.0}, heights = {0.0};
  double min_obstacle_distance_m = 0.0, max_extent_m = 3.0, clearance_m = 0.3;
  double max_range_m = 10.0;
  uint64_t min_cluster = 8;
  int viewpoints = 0, angles = 12, threads = 0;
  bool json = false;
};

nlohmann::json vec(const Eigen::Vector3d& v) { return {v.x(), v.y(), v.z()}; }

planning::GainSensor sensorFrom(const FrontierCommandOptions& o) {
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

void runFrontiers(const FrontierCommandOptions& o) {
  planning::FrontierFilter filter;
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
  planning::ClusterOptions cluster_options;
  cluster_options.min_cells = o.min_cluster;
  cluster_options.max_extent_m = o.max_extent_m;
  cluster_options.validate();
  if (o.viewpoints < 0)
    throw InvalidArgument(fmt::format("--viewpoints must be >= 0, got {}", o.viewpoints));
  planning::ViewpointOptions view_options;
  view_options.radii_m = o.radii;
  view_options.heights_m = o.heights;
  view_options.angles = o.angles;
  view_options.clearance_m = o.clearance_m;
  view_options.top_k = std::max(o.viewpoints, 1);
  view_options.sensor = sensorFrom(o);
  if (!o.robot.empty()) view_options.robot_m = Eigen::Vector3d(o.robot[0], o.robot[1], o.robot[2]);
  view_options.validate();
  if (o.threads < 0)
    throw InvalidArgument(fmt::format("--threads must be >= 0, got {}", o.threads));
  const Map map = loadMapFile(o.map);

  const auto t0 = std::chrono::steady_clock::now();
  const std::vector<VoxelKey> cells = planning::findFrontierCells(map, filter, o.threads);
  const auto t1 = std::chrono::steady_clock::now();
  planning::FrontierClusterer clusterer(cluster_options);
  const std::vector<planning::FrontierCluster> clusters = clusterer.cluster(map, cells);
  std::vector<std::vector<planning::Viewpoint>> views(clusters.size());
  if (o.viewpoints > 0)
    for (size_t i = 0; i < clusters.size(); ++i)
      views[i] = planning::clusterViewpoints(map, clusters[i], view_options);
  const auto t2 = std::chrono::steady_clock::now();
  const double cells_ms = std::chrono::duration<double, std::milli>(t1 - t0).count();
  const double rest_ms = std::chrono::duration<double, std::milli>(t2 - t1).count();

  if (o.json) {
    nlohmann::json js = nlohmann::json::array();
    for (size_t i = 0; i < clusters.size(); ++i) {
      const auto& c = clusters[i];
      nlohmann::json vs = nlohmann::json::array();
      for (const auto& v : views[i]) {
        nlohmann::json jv = {
            {"position", vec(v.position_m)}, {"yaw", v.yaw_rad}, {"gain_bits", v.gain_bits}};
        if (view_options.robot_m) {
          jv["distance"] = v.distance_m;
          jv["gain_per_metre"] = v.score;
        }
        vs.push_back(jv);
      }
      js.push_back({{"id", c.id},
                    {"cells", c.cells.size()},
                    {"centroid", vec(c.centroid_m)},
                    {"min", vec(c.min_m)},
                    {"max", vec(c.max_m)},
                    {"direction", vec(c.direction)},
                    {"viewpoints", vs}});
    }
    const nlohmann::json j = {{"frontier_cells", cells.size()},
                              {"clusters", js},
                              {"ms_cells", cells_ms},
                              {"ms_clusters_viewpoints", rest_ms}};
    std::printf("%s\n", j.dump().c_str());
    return;
  }
  std::printf("%s\n", fmt::format("{} frontier cells in {} clusters ({:.1f} ms cells, {:.1f} ms "
                                  "clusters and viewpoints)",
                                  cells.size(), clusters.size(), cells_ms, rest_ms)
                          .c_str());
  std::printf("%6s %7s %26s %22s %28s\n", "id", "cells", "centroid (m)", "direction",
              "best viewpoint (m, gain)");
  for (size_t i = 0; i < clusters.size(); ++i) {
    const auto& c = clusters[i];
    std::string best = "-";
    if (!views[i].empty())
      best = fmt::format("{:.2f} {:.2f} {:.2f} {:.0f} bit", views[i][0].position_m.x(),
                         views[i][0].position_m.y(), views[i][0].position_m.z(),
                         views[i][0].gain_bits);
    std::printf("%s\n",
                fmt::format("{:6} {:7} {:8.2f} {:8.2f} {:8.2f} {:6.2f} {:6.2f} {:6.2f}   {}", c.id,
                            c.cells.size(), c.centroid_m.x(), c.centroid_m.y(), c.centroid_m.z(),
                            c.direction.x(), c.direction.y(), c.direction.z(), best)
                    .c_str());
  }
}

}  // namespace

void addFrontiersCommand(CLI::App& app) {
  auto o = std::make_shared<FrontierCommandOptions>();
  CLI::App* c = app.add_subcommand(
      "frontiers",
      "Frontier cells (free cells with an unknown 26-neighbour), their clusters and the best "
      "viewpoints of each by information gain");
  c->add_option("map", o->map, "Map (.fgm, or .bt / .ot)")->required();
  c->add_option("--box", o->box, "Keep frontier cells with centres in X0 Y0 Z0 X1 Y1 Z1 (m)")
      ->expected(6);
  c->add_option("--height", o->height, "Keep frontier cells with centre z in MIN MAX (m)")
      ->expected(2);
  c->add_option("--min-obstacle-distance", o->min_obstacle_distance_m,
                "Drop frontier cells closer than M metres to an occupied cell (0: off)")
      ->capture_default_str();
  c->add_option("--min-cluster", o->min_cluster, "Drop clusters of fewer cells")
      ->capture_default_str();
  c->add_option("--max-extent", o->max_extent_m,
                "Split clusters wider than M metres along their principal axis (0: never)")
      ->capture_default_str();
  c->add_option("--viewpoints", o->viewpoints, "Best K viewpoints per cluster (0: none)")
      ->capture_default_str();
  c->add_option("--sensor", o->sensor, "Gain sensor: pinhole | lidar")->capture_default_str();
  c->add_option("--rays", o->rays,
                "Rays COLUMNS ROWS (pinhole default 64 48, lidar 360 azimuths x 16 beams)")
      ->expected(2);
  c->add_option("--fov", o->fov_deg, "Pinhole field of view H V in degrees (default 90 68.8)")
      ->expected(2);
  c->add_option("--elevation", o->elevation_deg, "LiDAR elevations MIN MAX, degrees (-15 15)")
      ->expected(2);
  c->add_option("--max-range", o->max_range_m, "Gain sensor range (m)")->capture_default_str();
  c->add_option("--radii", o->radii, "Viewpoint ring radii around each cluster (m)")
      ->capture_default_str();
  c->add_option("--heights", o->heights, "Viewpoint heights relative to the centroid (m)")
      ->capture_default_str();
  c->add_option("--angles", o->angles, "Viewpoints per ring")->capture_default_str();
  c->add_option("--clearance", o->clearance_m,
                "Free radius a viewpoint needs (no occupied or unknown cell), metres")
      ->capture_default_str();
  c->add_option("--robot", o->robot, "Rank viewpoints by gain per metre from X Y Z")->expected(3);
  c->add_option("--threads", o->threads, "CPU threads (0 = every core)")->capture_default_str();
  c->add_flag("--json", o->json, "Print one JSON object on stdout");
  c->callback([o] { runFrontiers(*o); });
}

}  // namespace fragg::cli
