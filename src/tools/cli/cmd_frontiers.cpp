// fragg_map frontiers MAP: frontier cells (free cells with an unknown 26-neighbour), their
// clusters and each cluster's best viewpoints by information gain.
#include <fmt/format.h>

#include <chrono>
#include <cstdio>
#include <memory>
#include <nlohmann/json.hpp>
#include <optional>
#include <string>
#include <vector>

#include "cli/commands.h"
#include "cli/frontier_options.h"
#include "cli/map_input.h"
#include "fragg_map/errors.h"
#include "fragg_map/planning/coarse_map.h"

namespace fragg::cli {

namespace {

struct FrontierCommandOptions {
  std::string map;
  FrontierFlags flags;
  bool json = false;
  int coarse_cells = 1;  ///< > 1: on the coarse map (planning/coarse_map.h)
};

nlohmann::json vec(const Eigen::Vector3d& v) { return {v.x(), v.y(), v.z()}; }

void runFrontiers(const FrontierCommandOptions& o) {
  const FrontierSettings settings = frontierSettings(o.flags);
  if (!planning::validCoarseCells(o.coarse_cells))
    throw InvalidArgument(
        fmt::format("--coarse-cells must be 1, 2, 4 or 8, got {}", o.coarse_cells));
  const Map loaded = loadMapFile(o.map);
  // With --coarse-cells the frontiers, clusters and viewpoints are those of the coarse map:
  // their cells are coarse cells (keys and centres at its resolution).
  std::optional<Map> coarse;
  const auto t0 = std::chrono::steady_clock::now();
  if (o.coarse_cells > 1) {
    if (settings.filter.use_box)  // only the part the query sees (same answer, less work)
      coarse.emplace(planning::coarseStateMapIn(
          loaded, o.coarse_cells, settings.filter.box_min_m, settings.filter.box_max_m,
          settings.filter.min_obstacle_distance_m +
              (settings.viewpoints > 0 ? planning::viewpointReachM(settings.views) : 0.0)));
    else
      coarse.emplace(planning::coarseStateMap(loaded, o.coarse_cells));
  }
  const double coarse_ms =
      std::chrono::duration<double, std::milli>(std::chrono::steady_clock::now() - t0).count();
  const Map& map = coarse ? *coarse : loaded;
  const FrontierResult r = computeFrontiers(map, settings);
  const auto& cells = r.cells;
  const auto& clusters = r.clusters;
  const auto& views = r.views;

  if (o.json) {
    nlohmann::json js = nlohmann::json::array();
    for (size_t i = 0; i < clusters.size(); ++i) {
      const auto& c = clusters[i];
      nlohmann::json vs = nlohmann::json::array();
      for (const auto& v : views[i]) {
        nlohmann::json jv = {
            {"position", vec(v.position_m)}, {"yaw", v.yaw_rad}, {"gain_bits", v.gain_bits}};
        if (settings.views.robot_m) {
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
    nlohmann::json j = {{"frontier_cells", cells.size()},
                        {"clusters", js},
                        {"ms_cells", r.cells_ms},
                        {"ms_clusters_viewpoints", r.clusters_viewpoints_ms}};
    if (settings.views.gain != planning::ViewpointGain::kEntropy)  // only when asked, as below
      j["gain"] = planning::viewpointGainName(settings.views.gain);
    if (o.coarse_cells > 1) {  // keys only when asked: the default JSON is unchanged
      j["coarse_cells"] = o.coarse_cells;
      j["frontier_resolution_m"] = map.resolution();
      j["ms_coarse_map"] = coarse_ms;
    }
    std::printf("%s\n", j.dump().c_str());
    return;
  }
  std::printf("%s\n",
              fmt::format("{} frontier cells in {} clusters ({:.1f} ms cells, {:.1f} ms "
                          "clusters and viewpoints)",
                          cells.size(), clusters.size(), r.cells_ms, r.clusters_viewpoints_ms)
                  .c_str());
  std::printf("%6s %7s %26s %22s %28s\n", "id", "cells", "centroid (m)", "direction",
              "best viewpoint (m, gain)");
  for (size_t i = 0; i < clusters.size(); ++i) {
    const auto& c = clusters[i];
    std::string best = "-";
    if (!views[i].empty())
      best =
          fmt::format("{:.2f} {:.2f} {:.2f} {:.0f} {}", views[i][0].position_m.x(),
                      views[i][0].position_m.y(), views[i][0].position_m.z(), views[i][0].gain_bits,
                      settings.views.gain == planning::ViewpointGain::kCoverage ? "cells" : "bit");
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
  addFrontierFlags(c, &o->flags);
  c->add_flag("--json", o->json, "Print one JSON object on stdout");
  c->add_option("--coarse-cells", o->coarse_cells,
                "Frontiers on a grid of N x N x N map cells (1, 2, 4, 8): a coarse cell is free "
                "when a cell is, unknown when all are (LiDAR gaps between beams vanish)")
      ->capture_default_str();
  c->callback([o] { runFrontiers(*o); });
}

}  // namespace fragg::cli
