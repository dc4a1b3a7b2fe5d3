// The frontier options `fragg_map frontiers` and `fragg_map render --frontiers` share: their
// command-line flags, their checks, and the computation (frontier cells, clusters, each
// cluster's best viewpoints) they run on a loaded map.
#pragma once

#include <CLI/CLI.hpp>
#include <cstdint>
#include <string>
#include <vector>

#include "fragg_map/map.h"
#include "fragg_map/planning/frontier_cells.h"
#include "fragg_map/planning/frontier_clusters.h"
#include "fragg_map/planning/viewpoints.h"

namespace fragg::cli {

/// The flags as given (degrees and whole numbers as the user types them).
struct FrontierFlags {
  std::string sensor = "pinhole";
  std::string gain = "entropy";  ///< planning::ViewpointGain by name
  std::vector<double> box, height, robot, rays, fov_deg, elevation_deg;
  std::vector<double> radii = {1.5, 3.0}, heights = {0.0};
  double min_obstacle_distance_m = 0.0, max_extent_m = 3.0, clearance_m = 0.3;
  double max_range_m = 10.0;
  uint64_t min_cluster = 8;
  int viewpoints = 0, angles = 12, threads = 0;
};

/// The flags turned into the library's options (validated).
struct FrontierSettings {
  planning::FrontierFilter filter;
  planning::ClusterOptions clusters;
  planning::ViewpointOptions views;  ///< top_k = max(viewpoints, 1)
  int viewpoints = 0;                ///< best K per cluster, 0: none computed
  int threads = 0;
};

struct FrontierResult {
  std::vector<VoxelKey> cells;  ///< every frontier cell passing the filter (frontierOrder)
  std::vector<planning::FrontierCluster> clusters;
  std::vector<std::vector<planning::Viewpoint>> views;  ///< per cluster (empty: none asked)
  double cells_ms = 0.0, clusters_viewpoints_ms = 0.0;
};

/// Registers --box, --height, --min-obstacle-distance, --min-cluster, --max-extent,
/// --viewpoints, --gain, --sensor, --rays, --fov, --elevation, --max-range, --radii,
/// --heights, --angles, --clearance, --robot and --threads on `cmd` (defaults from `*flags`). With
/// `needs` every one of them requires that flag (render: --frontiers).
void addFrontierFlags(CLI::App* cmd, FrontierFlags* flags, CLI::Option* needs = nullptr);

/// Throws InvalidArgument naming the flag for a bad value.
FrontierSettings frontierSettings(const FrontierFlags& flags);

/// Frontier cells, clusters (a fresh clusterer: ids 1, 2, ... by first cell) and viewpoints.
FrontierResult computeFrontiers(const Map& map, const FrontierSettings& settings);

}  // namespace fragg::cli
