// Closed-loop exploration in a simulated scene: frontiers (incremental tracker) -> clusters ->
// viewpoints -> move the sensor to the chosen viewpoint along a straight line -> simulate a scan
// there, integrate it -> repeat, until no viewpoint with gain is left or a budget runs out.
//
// Viewpoints. Each cluster's candidates (planning::clusterViewpoints: rings around it, clear of
// occupied and unknown cells, every candidate with gain) are computed when the cluster appears
// (a new id) and kept while its cells are unchanged, as FUEL updates only the frontiers a scan
// changed; a kept gain can be stale where a scan observed cells along its rays without changing
// the cluster's cells. Each step, the candidates are ranked from the sensor's position.
// Strategies. kGainPerMetre: the candidate of any cluster with the highest gain per metre of
// straight-line distance (gain / max(distance, voxel), as clusterViewpoints ranks with a robot
// position). kNearestFrontier (the baseline): the cluster whose centroid is nearest, the nearest
// of its candidates with gain, whatever the gain.
// Both skip a candidate whose straight path collides (planning::checkPath, a sphere of the
// robot's radius against the known occupied cells; unknown cells do not block the path, the
// viewpoint itself is clear of them); the first robot_radius_m of the path is not checked (the
// sensor is already there; a later scan may have put an occupied cell near it). A pose already
// scanned from is not chosen again, and a cluster that the last move went for and whose cells its
// scan left unchanged is left out (unexplorable from its viewpoints) while those cells stay so.
#pragma once

#include <Eigen/Core>
#include <cstdint>
#include <functional>
#include <string>
#include <vector>

#include "bench/explore/explored_volume.h"
#include "bench/explore/scenario.h"
#include "fragg_map/map_params.h"

namespace fragg::explore {

enum class Strategy { kGainPerMetre, kNearestFrontier };
const char* toString(Strategy s);
/// "gain" or "nearest"; throws InvalidArgument.
Strategy strategyFromString(const std::string& s);

struct ExploreLimits {
  int max_steps = 30;               ///< moves after the first scan, >= 1
  double max_path_m = 0.0;          ///< > 0: stop before a move would exceed it; 0: no limit
  double min_gain_bits = 1.0;       ///< viewpoints with less gain do not count, >= 0
  Backend backend = Backend::kCpu;  ///< map integration; collision checks run on the CPU
  int threads = 0;                  ///< 0 = every core
  /// Throws InvalidArgument naming the bad field.
  void validate() const;
};

struct StepRecord {
  int step = 0;  ///< 0: the scan at the start pose
  Eigen::Vector3d position_m = Eigen::Vector3d::Zero();
  double yaw_rad = 0.0;
  double path_m = 0.0;       ///< straight-line path length so far
  double gain_bits = 0.0;    ///< expected gain of the chosen viewpoint (0 at step 0)
  uint64_t known_cells = 0;  ///< reference cells known after this step's scan
  double explored = 0.0;     ///< known_cells / reference cells
  uint64_t frontier_cells = 0, clusters = 0;  ///< before choosing this step's viewpoint
  /// Clusters left out as unexplorable: a move went for them and its scan left their cells
  /// unchanged (kept out until their cells change).
  uint64_t unexplorable = 0;
  uint64_t viewpoints = 0;      ///< viewpoints with gain returned by clusterViewpoints
  uint64_t rejected_paths = 0;  ///< better viewpoints skipped: their path collides
  double frontier_ms = 0.0, cluster_ms = 0.0, gain_ms = 0.0, path_ms = 0.0;
  double simulate_ms = 0.0, insert_ms = 0.0;
};

struct ExploreRun {
  std::string scenario;
  Strategy strategy = Strategy::kGainPerMetre;
  std::vector<StepRecord> steps;
  std::string stop_reason;  ///< "no viewpoint with gain", "step budget", "path budget"
  /// Frontier cells and clusters of the last search (no viewpoint, or over the path budget).
  uint64_t final_frontier_cells = 0, final_clusters = 0;
  uint64_t reference_cells = 0;
  double cell_m3 = 0.0;
  std::string backend;  ///< the map's backend
};

/// Runs one exploration. `scene` is the scenario's scene as a BVH, `truth` its reference cells
/// at the scenario's resolution; `on_step` (optional) sees each step's record as it is made.
/// Throws InvalidArgument for a bad scenario or limits.
ExploreRun explore(const Scenario& scenario, const geometry::MeshBvh& scene,
                   const ExploredVolume& truth, Strategy strategy, const ExploreLimits& limits,
                   const std::function<void(const StepRecord&)>& on_step = nullptr);

/// CSV of runs: a header, then one row per step of each run. Timing columns (milliseconds)
/// only with `with_times` (without them two runs of the same arguments give the same text).
std::string toCsv(const std::vector<ExploreRun>& runs, bool with_times);

}  // namespace fragg::explore
