#include "bench/explore/explorer.h"

#include <fmt/format.h>

#include <algorithm>
#include <chrono>
#include <cmath>
#include <optional>
#include <unordered_map>
#include <unordered_set>

#include "fragg_map/errors.h"
#include "fragg_map/geometry/mesh_bvh.h"
#include "fragg_map/map.h"
#include "fragg_map/planning/collision_shape.h"
#include "fragg_map/planning/frontier_tracker.h"
#include "fragg_map/planning/path_check.h"

namespace fragg::explore {
namespace {

using Clock = std::chrono::steady_clock;

double msSince(Clock::time_point t0) {
  return std::chrono::duration<double, std::milli>(Clock::now() - t0).count();
}

Eigen::Isometry3d at(const Eigen::Vector3d& p_m) {
  Eigen::Isometry3d T = Eigen::Isometry3d::Identity();
  T.translation() = p_m;
  return T;
}

/// The viewpoint heights (offsets from the centroid's z) for one cluster.
std::vector<double> heightsFor(const Scenario& s, const planning::FrontierCluster& c) {
  const Eigen::Vector3d& g = c.centroid_m;
  double z_m = 0.0;
  if (s.ground_height_m > 0.0) {
    z_m = s.scene.terrain.heightAt(g.x(), g.y()) + s.ground_height_m;
  } else {
    z_m = std::clamp(g.z(), s.min_sensor_z_m, s.max_sensor_z_m);
  }
  return {z_m - g.z()};
}

/// Whether the sphere can move straight from `from_m` to `to_m` without touching a known
/// occupied cell (the first robot radius of the way not checked, see explorer.h).
bool pathFree(const Map& map, const planning::CollisionShape& robot, const Eigen::Vector3d& from_m,
              const Eigen::Vector3d& to_m, const planning::CollisionOptions& options) {
  const Eigen::Vector3d d = to_m - from_m;
  const double length_m = d.norm();
  const double skip_m = robot.radius();
  std::vector<Eigen::Isometry3d> waypoints;
  if (length_m > skip_m) waypoints.push_back(at(from_m + d * (skip_m / length_m)));
  waypoints.push_back(at(to_m));
  return !planning::checkPath(map, robot, waypoints, options).collides;
}

struct Choice {
  planning::Viewpoint viewpoint;
  uint64_t cluster_id = 0;
  uint64_t viewpoints = 0, rejected = 0;
  double path_ms = 0.0;
};

/// Every candidate viewpoint with gain of each live cluster, ranked by gain; computed when the
/// cluster appears (a new id) and kept while its cells are unchanged (see explorer.h).
using ViewpointCache = std::unordered_map<uint64_t, std::vector<planning::Viewpoint>>;

std::optional<Choice> choose(const Map& map, const Scenario& s, Strategy strategy,
                             const std::vector<planning::FrontierCluster>& clusters,
                             const Eigen::Vector3d& robot_m, const ExploreLimits& limits,
                             const std::vector<Eigen::Vector4d>& scanned, ViewpointCache* cache,
                             double* gain_ms) {
  const planning::CollisionShape robot = planning::CollisionShape::sphere(s.robot_radius_m);
  planning::CollisionOptions collision;
  collision.threads = limits.threads;
  Choice choice;

  // Forget clusters gone; new ones are scored when first asked for (the baseline asks for few).
  std::unordered_set<uint64_t> live;
  for (const auto& c : clusters) live.insert(c.id);
  for (auto it = cache->begin(); it != cache->end();)
    it = live.count(it->first) ? std::next(it) : cache->erase(it);
  auto viewpointsOf = [&](const planning::FrontierCluster& c) -> const auto& {
    auto found = cache->find(c.id);
    if (found != cache->end()) return found->second;
    planning::ViewpointOptions o = s.viewpoints;
    o.heights_m = heightsFor(s, c);
    o.top_k = int(s.viewpoints.radii_m.size()) * s.viewpoints.angles;
    const auto t0 = Clock::now();
    auto& v = (*cache)[c.id] = planning::clusterViewpoints(map, c, o);
    *gain_ms += msSince(t0);
    return v;
  };

  // This step's candidates: distance and gain per metre from the robot (as clusterViewpoints
  // ranks them with a robot position), without poses already scanned from: a scan again from
  // there sees the same cells, so its gain (cells the sensor cannot resolve from there, e.g.
  // left in the unknown band) is not to be had.
  const double same_m = 0.5 * map.resolution();
  auto repeated = [&](const planning::Viewpoint& p) {
    for (const Eigen::Vector4d& q : scanned)
      if ((q.head<3>() - p.position_m).norm() < same_m && std::abs(q.w() - p.yaw_rad) < 1e-6)
        return true;
    return false;
  };
  auto candidatesOf = [&](const planning::FrontierCluster& c) {
    std::vector<planning::Viewpoint> v;
    for (planning::Viewpoint p : viewpointsOf(c)) {
      if (p.gain_bits < limits.min_gain_bits || repeated(p)) continue;
      p.distance_m = (p.position_m - robot_m).norm();
      p.score = p.gain_bits / std::max(p.distance_m, map.resolution());
      v.push_back(p);
    }
    choice.viewpoints += v.size();
    return v;
  };
  auto free = [&](const planning::Viewpoint& v) {
    const auto t1 = Clock::now();
    const bool ok = pathFree(map, robot, robot_m, v.position_m, collision);
    choice.path_ms += msSince(t1);
    if (!ok) ++choice.rejected;
    return ok;
  };

  if (strategy == Strategy::kGainPerMetre) {
    std::vector<std::pair<planning::Viewpoint, uint64_t>> all;  // viewpoint, cluster id
    for (const auto& c : clusters)
      for (const auto& v : candidatesOf(c)) all.emplace_back(v, c.id);
    std::stable_sort(all.begin(), all.end(),
                     [](const auto& a, const auto& b) { return a.first.score > b.first.score; });
    for (const auto& [v, id] : all) {
      if (free(v)) {
        choice.viewpoint = v;
        choice.cluster_id = id;
        return choice;
      }
    }
    return std::nullopt;
  }
  // Nearest frontier: clusters by centroid distance, then the cluster's viewpoints by distance.
  std::vector<size_t> order(clusters.size());
  for (size_t i = 0; i < order.size(); ++i) order[i] = i;
  std::stable_sort(order.begin(), order.end(), [&](size_t a, size_t b) {
    return (clusters[a].centroid_m - robot_m).squaredNorm() <
           (clusters[b].centroid_m - robot_m).squaredNorm();
  });
  for (size_t i : order) {
    auto v = candidatesOf(clusters[i]);
    std::stable_sort(v.begin(), v.end(),
                     [](const planning::Viewpoint& a, const planning::Viewpoint& b) {
                       return a.distance_m < b.distance_m;
                     });
    for (const auto& p : v) {
      if (free(p)) {
        choice.viewpoint = p;
        choice.cluster_id = clusters[i].id;
        return choice;
      }
    }
  }
  return std::nullopt;
}

}  // namespace

const char* toString(Strategy s) { return s == Strategy::kGainPerMetre ? "gain" : "nearest"; }

Strategy strategyFromString(const std::string& s) {
  if (s == "gain") return Strategy::kGainPerMetre;
  if (s == "nearest") return Strategy::kNearestFrontier;
  throw InvalidArgument("strategy must be gain or nearest, not '" + s + "'");
}

void ExploreLimits::validate() const {
  if (max_steps < 1) throw InvalidArgument("max_steps must be >= 1");
  if (!(max_path_m >= 0.0) || !std::isfinite(max_path_m))
    throw InvalidArgument("max_path_m must be finite and >= 0");
  if (!(min_gain_bits >= 0.0) || !std::isfinite(min_gain_bits))
    throw InvalidArgument("min_gain_bits must be finite and >= 0");
  if (threads < 0) throw InvalidArgument("threads must be >= 0");
}

ExploreRun explore(const Scenario& scenario, const geometry::MeshBvh& scene,
                   const ExploredVolume& truth, Strategy strategy, const ExploreLimits& limits,
                   const std::function<void(const StepRecord&)>& on_step) {
  scenario.validate();
  limits.validate();
  MapParams params;
  params.resolution_m = scenario.resolution_m;
  params.backend = limits.backend;
  params.threads = limits.threads;
  params.clear_no_return_rays = true;  // the simulated clouds are organised
  Map map(params);
  const SensorModel model = integrationModel(scenario);

  planning::FrontierFilter filter;
  filter.use_box = true;
  filter.box_min_m = scenario.box_min_m;
  filter.box_max_m = scenario.box_max_m;
  planning::FrontierTracker tracker(filter, limits.threads);
  planning::FrontierClusterer clusterer(scenario.clusters);

  ExploreRun run;
  run.scenario = scenario.name;
  run.strategy = strategy;
  run.reference_cells = truth.referenceCells();
  run.cell_m3 = truth.cellVolume_m3();
  run.backend = map.backendName();

  std::vector<Eigen::Vector4d> scanned;  // x, y, z, yaw of every scan so far
  std::unordered_set<uint64_t> unexplorable;
  uint64_t target_cluster = 0;
  ViewpointCache cache;
  StepRecord rec;
  rec.position_m = scenario.start_m;
  rec.yaw_rad = scenario.start_yaw_rad;
  for (int step = 0;; ++step) {
    rec.step = step;
    // Scan at the current pose, integrate it, measure.
    const Eigen::Isometry3d T_map_sensor = sensorPose(scenario, rec.position_m, rec.yaw_rad);
    auto t0 = Clock::now();
    const PointCloud cloud = simulateScan(scenario, scene, T_map_sensor, uint64_t(step));
    rec.simulate_ms = msSince(t0);
    t0 = Clock::now();
    map.insert(cloud, T_map_sensor, model);
    rec.insert_ms = msSince(t0);
    scanned.emplace_back(rec.position_m.x(), rec.position_m.y(), rec.position_m.z(), rec.yaw_rad);
    rec.known_cells = truth.knownReferenceCells(map);
    rec.explored =
        run.reference_cells ? double(rec.known_cells) / double(run.reference_cells) : 0.0;
    run.steps.push_back(rec);
    if (on_step) on_step(rec);
    if (step >= limits.max_steps) {
      run.stop_reason = "step budget";
      break;
    }

    // Choose the next viewpoint.
    rec = StepRecord();
    const StepRecord& last = run.steps.back();
    t0 = Clock::now();
    tracker.update(map);
    const std::vector<VoxelKey> cells = tracker.cells();
    rec.frontier_ms = msSince(t0);
    rec.frontier_cells = cells.size();
    t0 = Clock::now();
    std::vector<planning::FrontierCluster> clusters = clusterer.cluster(map, cells);
    rec.cluster_ms = msSince(t0);
    rec.clusters = clusters.size();
    // The cluster the last move went for, unchanged by the scan there (same id: same cells),
    // cannot be explored from its viewpoints: left out from now on (until its cells change).
    if (target_cluster != 0 &&
        std::any_of(clusters.begin(), clusters.end(),
                    [&](const planning::FrontierCluster& c) { return c.id == target_cluster; }))
      unexplorable.insert(target_cluster);
    clusters.erase(std::remove_if(clusters.begin(), clusters.end(),
                                  [&](const planning::FrontierCluster& c) {
                                    return unexplorable.count(c.id) > 0;
                                  }),
                   clusters.end());
    rec.unexplorable = rec.clusters - clusters.size();
    const std::optional<Choice> choice = choose(map, scenario, strategy, clusters, last.position_m,
                                                limits, scanned, &cache, &rec.gain_ms);
    if (!choice) {
      run.stop_reason = "no viewpoint with gain";
      run.final_frontier_cells = rec.frontier_cells;
      run.final_clusters = rec.clusters;
      break;
    }
    const double move_m = (choice->viewpoint.position_m - last.position_m).norm();
    if (limits.max_path_m > 0.0 && last.path_m + move_m > limits.max_path_m) {
      run.stop_reason = "path budget";
      run.final_frontier_cells = rec.frontier_cells;
      run.final_clusters = rec.clusters;
      break;
    }
    rec.path_ms = choice->path_ms;
    rec.viewpoints = choice->viewpoints;
    rec.rejected_paths = choice->rejected;
    rec.position_m = choice->viewpoint.position_m;
    rec.yaw_rad = choice->viewpoint.yaw_rad;
    rec.gain_bits = choice->viewpoint.gain_bits;
    target_cluster = choice->cluster_id;
    rec.path_m = last.path_m + move_m;
  }
  return run;
}

std::string toCsv(const std::vector<ExploreRun>& runs, bool with_times) {
  std::string out =
      "scenario,strategy,step,x_m,y_m,z_m,yaw_rad,path_m,gain_bits,known_cells,reference_cells,"
      "explored,known_m3,frontier_cells,clusters,unexplorable_clusters,viewpoints,rejected_paths";
  if (with_times) out += ",frontier_ms,cluster_ms,gain_ms,path_ms,simulate_ms,insert_ms";
  out += "\n";
  for (const ExploreRun& r : runs) {
    for (const StepRecord& s : r.steps) {
      out += fmt::format(
          "{},{},{},{:.4f},{:.4f},{:.4f},{:.5f},{:.4f},{:.2f},{},{},{:.6f},{:.3f},{},{},"
          "{},{},{}",
          r.scenario, toString(r.strategy), s.step, s.position_m.x(), s.position_m.y(),
          s.position_m.z(), s.yaw_rad, s.path_m, s.gain_bits, s.known_cells, r.reference_cells,
          s.explored, double(s.known_cells) * r.cell_m3, s.frontier_cells, s.clusters,
          s.unexplorable, s.viewpoints, s.rejected_paths);
      if (with_times)
        out += fmt::format(",{:.2f},{:.2f},{:.2f},{:.2f},{:.2f},{:.2f}", s.frontier_ms,
                           s.cluster_ms, s.gain_ms, s.path_ms, s.simulate_ms, s.insert_ms);
      out += "\n";
    }
  }
  return out;
}

}  // namespace fragg::explore
