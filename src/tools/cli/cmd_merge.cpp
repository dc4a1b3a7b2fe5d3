// fragg_map merge BASE SUB... -o OUT.fgm --mode overwrite|add [--transform X Y Z QX QY QZ QW]:
// merges sub-maps (or maps from another robot) into a base map (Map::merge).
#include <fmt/format.h>

#include <chrono>
#include <cmath>
#include <cstdio>
#include <nlohmann/json.hpp>
#include <optional>
#include <string>
#include <vector>

#include "cli/commands.h"
#include "cli/map_input.h"
#include "fragg_map/atomic_file.h"
#include "fragg_map/errors.h"
#include "fragg_map/map.h"

namespace fragg::cli {

namespace {
struct MergeOptions {
  std::string base, output, mode;
  std::vector<std::string> subs;
  std::vector<double> transform;
  bool json = false;
};

/// T_map_sub from X Y Z QX QY QZ QW; the quaternion must be unit within 1e-6.
Eigen::Isometry3d poseOf(const std::vector<double>& v) {
  for (double x : v)
    if (!std::isfinite(x)) throw InvalidArgument("--transform values must be finite");
  const Eigen::Quaterniond q(v[6], v[3], v[4], v[5]);
  if (std::fabs(q.norm() - 1.0) > 1e-6)
    throw InvalidArgument(fmt::format(
        "--transform quaternion is not unit (norm {:.9f}; must be 1 within 1e-6)", q.norm()));
  Eigen::Isometry3d T = Eigen::Isometry3d::Identity();
  T.linear() = q.normalized().toRotationMatrix();
  T.translation() = Eigen::Vector3d(v[0], v[1], v[2]);
  return T;
}

void runMerge(const MergeOptions& o) {
  const MergeMode mode = mergeModeFromString(o.mode);
  std::optional<Eigen::Isometry3d> T_map_sub;
  if (!o.transform.empty()) T_map_sub = poseOf(o.transform);
  if (extensionOf(o.output) != "fgm")
    throw InvalidArgument("output must be a .fgm file, got '" + o.output + "'");
  checkOutputDirectory(o.output);
  { AtomicFile probe(o.output); }  // fail now, not after the merge
  Map map = loadMapFile(o.base);
  // Every sub-map is read (and rejected if unreadable) before the base changes.
  std::vector<Map> subs;
  for (const std::string& path : o.subs) subs.push_back(loadMapFile(path));
  const auto t0 = std::chrono::steady_clock::now();
  SubmapStats total;
  for (size_t k = 0; k < subs.size(); ++k) {
    try {
      const SubmapStats st = map.merge(subs[k], mode, T_map_sub);
      total.cells += st.cells;
      total.blocks += st.blocks;
    } catch (const InvalidArgument& e) {
      throw InvalidArgument(o.subs[k] + ": " + e.what());
    }
  }
  const double ms =
      std::chrono::duration<double, std::milli>(std::chrono::steady_clock::now() - t0).count();
  map.save(o.output);
  if (o.json) {
    nlohmann::json j = {{"output", o.output},
                        {"mode", toString(mode)},
                        {"sub_maps", subs.size()},
                        {"cells_merged", total.cells},
                        {"blocks_merged", total.blocks},
                        {"known_voxels", map.knownVoxelCount()},
                        {"ms", ms}};
    std::printf("%s\n", j.dump().c_str());
    return;
  }
  std::printf("%s\n", fmt::format("merged {} cells of {} sub-map(s) ({}), {} blocks written, in "
                                  "{:.1f} ms; wrote {} ({} known voxels)",
                                  total.cells, subs.size(), toString(mode), total.blocks, ms,
                                  o.output, map.knownVoxelCount())
                          .c_str());
}
}  // namespace

void addMergeCommand(CLI::App& app) {
  auto o = std::make_shared<MergeOptions>();
  CLI::App* c = app.add_subcommand(
      "merge", "Merge sub-maps (or maps of the same resolution and occupancy model) into a map");
  c->add_option("base", o->base, "Map merged into (.fgm, or .bt/.ot)")->required();
  c->add_option("sub", o->subs, "Sub-maps, merged in order")->required();
  c->add_option("-o,--output", o->output, "Merged map to write (.fgm)")->required();
  c->add_option("--mode", o->mode,
                "overwrite (observed sub-map cells replace the map's) | add (log-odds add, "
                "clamped; hit counts add)")
      ->required();
  c->add_option("--transform", o->transform,
                "T_map_sub for every sub-map: X Y Z QX QY QZ QW (metres, unit quaternion); "
                "whole-voxel translations are exact, other poses are resampled")
      ->expected(7);
  c->add_flag("--json", o->json, "Print one JSON object on stdout");
  c->callback([o] { runMerge(*o); });
}

}  // namespace fragg::cli
