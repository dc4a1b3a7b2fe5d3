// fragg_map truncate MAP (--box X0 Y0 Z0 X1 Y1 Z1 | --center X Y Z --radius R) -o SUB.fgm
// [--rest REST.fgm]: cuts a sub-map out of a map (Map::truncate / Map::truncateOutside).
#include <fmt/format.h>

#include <chrono>
#include <cstdio>
#include <nlohmann/json.hpp>
#include <string>
#include <vector>

#include "cli/commands.h"
#include "cli/map_input.h"
#include "fragg_map/atomic_file.h"
#include "fragg_map/errors.h"
#include "fragg_map/map.h"

namespace fragg::cli {

namespace {
struct TruncateOptions {
  std::string map, output, rest;
  std::vector<double> box, center;
  double radius_m = -1.0;
  bool has_radius = false;
  bool json = false;
};

void requireFgmOutput(const std::string& path, const char* what) {
  if (extensionOf(path) != "fgm")
    throw InvalidArgument(std::string(what) + " must be a .fgm file, got '" + path + "'");
  checkOutputDirectory(path);
  AtomicFile probe(path);  // fail now, not after the cut
}

void runTruncate(const TruncateOptions& o) {
  const bool by_box = !o.box.empty();
  const bool by_sphere = !o.center.empty() || o.has_radius;
  if (by_box == by_sphere)
    throw InvalidArgument("give either --box X0 Y0 Z0 X1 Y1 Z1 or --center X Y Z --radius R");
  if (by_sphere && (o.center.empty() || !o.has_radius))
    throw InvalidArgument("--center and --radius go together");
  requireFgmOutput(o.output, "output");
  if (!o.rest.empty()) requireFgmOutput(o.rest, "--rest");
  // The region is checked before the map is read.
  const SubmapRegion region =
      by_box ? SubmapRegion::box(Eigen::Vector3d(o.box[0], o.box[1], o.box[2]),
                                 Eigen::Vector3d(o.box[3], o.box[4], o.box[5]))
             : SubmapRegion::outsideSphere(Eigen::Vector3d(o.center[0], o.center[1], o.center[2]),
                                           o.radius_m);
  Map map = loadMapFile(o.map);
  const auto t0 = std::chrono::steady_clock::now();
  SubmapStats st;
  const Map sub = by_box
                      ? map.truncate(region.min_map, region.max_map, Backend::kCpu, &st)
                      : map.truncateOutside(region.center_map, region.radius_m, Backend::kCpu, &st);
  const double ms =
      std::chrono::duration<double, std::milli>(std::chrono::steady_clock::now() - t0).count();
  sub.save(o.output);
  if (!o.rest.empty()) map.save(o.rest);
  if (o.json) {
    nlohmann::json j = {{"output", o.output},
                        {"region", by_box ? "box" : "outside_sphere"},
                        {"cells_moved", st.cells},
                        {"blocks_moved", st.blocks},
                        {"blocks_erased", st.blocks_erased},
                        {"cells_left", map.knownVoxelCount()},
                        {"ms", ms}};
    if (!o.rest.empty()) j["rest"] = o.rest;
    std::printf("%s\n", j.dump().c_str());
    return;
  }
  std::printf(
      "%s\n",
      fmt::format("moved {} cells in {} blocks ({}) to {} in {:.1f} ms; {} cells left{}", st.cells,
                  st.blocks, by_box ? "inside the box" : "farther than the radius", o.output, ms,
                  map.knownVoxelCount(), o.rest.empty() ? "" : " (written to " + o.rest + ")")
          .c_str());
}
}  // namespace

void addTruncateCommand(CLI::App& app) {
  auto o = std::make_shared<TruncateOptions>();
  CLI::App* c = app.add_subcommand(
      "truncate",
      "Cut a sub-map out of a map: the cells whose centres lie in a box, or farther than a "
      "radius from a centre");
  c->add_option("map", o->map, "Map to cut (.fgm, or .bt/.ot)")->required();
  c->add_option("--box", o->box, "Box in the map frame, metres: X0 Y0 Z0 X1 Y1 Z1")->expected(6);
  c->add_option("--center", o->center, "Centre in the map frame, metres: X Y Z")->expected(3);
  c->add_option_function<double>(
      "--radius",
      [o](double r) {
        o->radius_m = r;
        o->has_radius = true;
      },
      "With --center: the sub-map holds the cells farther than R metres");
  c->add_option("-o,--output", o->output, "Sub-map to write (.fgm, with its region)")->required();
  c->add_option("--rest", o->rest, "Also write what the map keeps (.fgm)");
  c->add_flag("--json", o->json, "Print one JSON object on stdout");
  c->callback([o] { runTruncate(*o); });
}

}  // namespace fragg::cli
