// fragg_map eval MAP --scene SCENE.obj: map quality against the ground-truth scene, and the
// same figures for OctoMap's map of the same data (--octomap X.bt), side by side; with
// --labels, SA, DA and ghost cells against a labelled dataset and the static truth.
#include <fmt/format.h>

#include <chrono>
#include <cstdio>
#include <limits>
#include <memory>
#include <nlohmann/json.hpp>
#include <string>
#include <vector>

#include "cli/commands.h"
#include "cli/map_input.h"
#include "fragg_map/errors.h"
#include "fragg_map/geometry/mesh_bvh.h"
#include "fragg_map/geometry/obj_file.h"
#include "fragg_map/io/dataset.h"
#include "fragg_map/sim/dataset_writers.h"
#include "fragg_map/sim/dynamic_quality.h"
#include "fragg_map/sim/map_quality.h"
#include "fragg_map/sim/scene.h"

namespace fragg::cli {
namespace {

struct EvalOptions {
  std::string map, scene, octomap;
  bool json = false, octomap_threshold = false;
  std::string labels;  ///< labelled dataset (labels/*.dyn): SA, DA, ghost cells
  size_t label_every = 1, label_scans = 0;
  double label_max_range_m = -1.0;
};

constexpr const char* kDynamicMetrics =
    "\nWith --labels DATASET (a dataset folder with labels/*.dyn, as fragg_map_sim writes for "
    "scenes with movers; --scene is then the static truth), the KTH DynamicMap benchmark's "
    "metrics (arXiv 2307.07260) over the labelled points of the scans (ground-truth poses):\n"
    "  SA          static points whose voxel is occupied / static points\n"
    "  DA          dynamic points whose voxel is not occupied / dynamic points\n"
    "  ghost cells occupied voxels farther than d from the static surface and outside its "
    "solids (free in the static truth: what movers left behind)";

// SA, DA and ghost cells of one map against the labelled dataset and the static truth.
sim::DynamicQuality dynamicQuality(const Map& map, const geometry::MeshBvh& scene,
                                   const EvalOptions& o) {
  sim::DynamicQuality q;
  sim::countGhostCells(map, scene, o.octomap_threshold, q);
  std::unique_ptr<ScanSource> source = openDataset(o.labels);
  Scan scan;
  for (size_t i = 0; source->next(scan); ++i) {
    if (o.label_scans > 0 && i >= o.label_scans) break;
    if (i % o.label_every != 0) continue;
    try {
      sim::addLabelledScan(
          map, scan.cloud, scan.T_map_sensor, sim::readDynamicLabels(o.labels, i),
          o.octomap_threshold, q,
          o.label_max_range_m > 0 ? o.label_max_range_m : std::numeric_limits<double>::infinity());
    } catch (const InvalidArgument& e) {
      throw InvalidArgument("--labels: scan " + std::to_string(i) + ": " + e.what());
    }
  }
  return q;
}

nlohmann::json toJson(const sim::DynamicQuality& q) {
  return {{"static_points", q.static_points},
          {"static_kept", q.static_kept},
          {"dynamic_points", q.dynamic_points},
          {"dynamic_removed", q.dynamic_removed},
          {"sa", q.staticAccuracy()},
          {"da", q.dynamicAccuracy()},
          {"occupied", q.occupied},
          {"ghost_cells", q.ghost_cells}};
}

constexpr const char* kMetrics =
    "Map quality against the ground-truth scene (map frame = scene frame). With res the voxel "
    "edge and d = sqrt(3)/2 * res (half a voxel diagonal):\n"
    "  precision   occupied voxels whose centre is within d of the scene surface / occupied "
    "voxels\n"
    "  recall      surface voxels (voxels whose cube the surface passes through) in the observed "
    "region that are occupied / surface voxels in the observed region; a voxel is in the "
    "observed region when it or one of its 26 neighbours is known (observed)\n"
    "  recall, known surface   the same over the surface voxels that are known themselves "
    "(observed surface that stayed occupied)\n"
    "  free error  free voxels whose centre is inside a solid of the scene / free voxels (and "
    "the count); 'deep' counts only those farther than d from the surface\n"
    "Cell states follow each map's own rule (unknown band; a .bt import keeps fragg's default "
    "band), or OctoMap's with --octomap-threshold (observed: occupied iff p >= 0.5).";

// What each row of the text report measures (a bare "recall 6.8 %" reads as a failure when it
// is what a sparse sensor gives).
constexpr const char* kLegend =
    "what the rows measure (d = half a voxel diagonal; higher is better for precision and "
    "recall, lower for free error):\n"
    "  precision   share of the occupied voxels that lie on the scene's surface (within d)\n"
    "  recall      share of the surface voxels in the observed region that are occupied; a "
    "sensor with few beams or poses sees a small part of each surface near the known cells, so "
    "a low recall is expected from sparse scans\n"
    "  recall, known surface   the same over the surface voxels the map knows\n"
    "  free error  share of the free voxels whose centre lies inside a solid (the count in "
    "brackets)\n";

nlohmann::json toJson(const sim::MapQuality& q, const std::string& path, double seconds) {
  return {{"map", path},
          {"resolution_m", q.resolution_m},
          {"occupied", q.occupied},
          {"occupied_near_surface", q.occupied_near_surface},
          {"precision", q.precision()},
          {"surface_observed", q.surface_observed},
          {"surface_observed_occupied", q.surface_observed_occupied},
          {"recall", q.recall()},
          {"surface_known", q.surface_known},
          {"known_surface_recall", q.knownSurfaceRecall()},
          {"free", q.free},
          {"free_inside", q.free_inside},
          {"free_inside_deep", q.free_inside_deep},
          {"free_error", q.freeError()},
          {"free_error_deep", q.freeErrorDeep()},
          {"seconds", seconds}};
}

void runEval(const EvalOptions& o) {
  const std::string ext = extensionOf(o.scene);
  if (ext != "obj" && ext != "json")
    throw InvalidArgument("--scene must be an OBJ file or a fragg_map_sim scene (.json)");
  geometry::TriangleMesh mesh =
      ext == "obj" ? geometry::readObj(o.scene) : sim::loadScene(o.scene).mesh;
  const geometry::MeshBvh scene(std::move(mesh));
  sim::MapQualityOptions options;
  options.octomap_threshold = o.octomap_threshold;

  std::vector<std::string> paths = {o.map};
  if (!o.octomap.empty()) paths.push_back(o.octomap);
  if (o.label_every < 1) throw InvalidArgument("--label-every must be >= 1");
  std::vector<sim::MapQuality> results;
  std::vector<sim::DynamicQuality> dynamic;
  std::vector<double> seconds;
  for (const std::string& path : paths) {
    const Map map = loadMapFile(path);
    const auto t0 = std::chrono::steady_clock::now();
    results.push_back(sim::evaluateMapQuality(map, scene, options));
    if (!o.labels.empty()) dynamic.push_back(dynamicQuality(map, scene, o));
    seconds.push_back(std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count());
  }
  if (o.json) {
    nlohmann::json j = {{"scene", o.scene},
                        {"octomap_threshold", o.octomap_threshold},
                        {"map", toJson(results[0], paths[0], seconds[0])}};
    if (results.size() > 1) j["octomap"] = toJson(results[1], paths[1], seconds[1]);
    if (!o.labels.empty()) {
      j["labels"] = o.labels;
      j["map"]["dynamic"] = toJson(dynamic[0]);
      if (dynamic.size() > 1) j["octomap"]["dynamic"] = toJson(dynamic[1]);
    }
    std::printf("%s\n", j.dump().c_str());
    return;
  }
  std::string out =
      fmt::format("scene {} ({} triangles), states: {}\n", o.scene, scene.mesh().size(),
                  o.octomap_threshold ? "OctoMap's rule" : "each map's own rule");
  out += fmt::format("{:<28}", "");
  for (const std::string& p : paths)
    out += fmt::format(" | {:>26}", p.size() > 26 ? "..." + p.substr(p.size() - 23) : p);
  out += "\n";
  auto row = [&](const char* name, auto value) {
    out += fmt::format("{:<28}", name);
    for (const sim::MapQuality& q : results) out += fmt::format(" | {:>26}", value(q));
    out += "\n";
  };
  row("precision", [](const sim::MapQuality& q) {
    return fmt::format("{:.4f} % of {}", 100 * q.precision(), q.occupied);
  });
  row("recall", [](const sim::MapQuality& q) {
    return fmt::format("{:.4f} % of {}", 100 * q.recall(), q.surface_observed);
  });
  row("recall, known surface", [](const sim::MapQuality& q) {
    return fmt::format("{:.4f} % of {}", 100 * q.knownSurfaceRecall(), q.surface_known);
  });
  row("free error", [](const sim::MapQuality& q) {
    return fmt::format("{:.5f} % ({})", 100 * q.freeError(), q.free_inside);
  });
  row("free error, deeper than d", [](const sim::MapQuality& q) {
    return fmt::format("{:.5f} % ({})", 100 * q.freeErrorDeep(), q.free_inside_deep);
  });
  row("free voxels", [](const sim::MapQuality& q) { return fmt::format("{}", q.free); });
  if (!dynamic.empty()) {
    auto drow = [&](const char* name, auto value) {
      out += fmt::format("{:<28}", name);
      for (const sim::DynamicQuality& q : dynamic) out += fmt::format(" | {:>26}", value(q));
      out += "\n";
    };
    drow("SA (static points kept)", [](const sim::DynamicQuality& q) {
      return fmt::format("{:.3f} % of {}", 100 * q.staticAccuracy(), q.static_points);
    });
    drow("DA (dynamic points removed)", [](const sim::DynamicQuality& q) {
      return fmt::format("{:.3f} % of {}", 100 * q.dynamicAccuracy(), q.dynamic_points);
    });
    drow("ghost cells", [](const sim::DynamicQuality& q) {
      return fmt::format("{} of {} occupied", q.ghost_cells, q.occupied);
    });
  }
  out += kLegend;
  std::printf("%s", out.c_str());
}

}  // namespace

void addEvalCommand(CLI::App& app) {
  auto o = std::make_shared<EvalOptions>();
  CLI::App* c = app.add_subcommand("eval", "Map quality against the ground-truth scene");
  c->footer(std::string(kMetrics) + kDynamicMetrics);
  c->add_option("map", o->map, "Map to evaluate (.fgm, or .bt/.ot)")->required();
  c->add_option("--scene", o->scene,
                "Ground truth: OBJ of closed solids (fragg_map_sim scene / record --obj) or a "
                "scene file (.json)")
      ->required();
  c->add_option("--octomap", o->octomap, "OctoMap's map of the same data (.bt), side by side");
  c->add_flag("--octomap-threshold", o->octomap_threshold,
              "Classify observed cells as OctoMap does (occupied iff p >= 0.5)");
  c->add_option("--labels", o->labels,
                "Labelled dataset (folder with labels/*.dyn): SA, DA and ghost cells against "
                "the static truth --scene");
  c->add_option("--label-every", o->label_every, "With --labels: every Nth scan")
      ->capture_default_str();
  c->add_option("--label-scans", o->label_scans,
                "With --labels: the first N scans (0 = all; give the build's --scans)")
      ->capture_default_str();
  c->add_option("--label-max-range", o->label_max_range_m,
                "With --labels: only points within this range of the sensor (m; give the "
                "build's --max-range; <= 0: all)")
      ->capture_default_str();
  c->add_flag("--json", o->json, "Print one JSON object on stdout");
  c->callback([o] { runEval(*o); });
}

}  // namespace fragg::cli
