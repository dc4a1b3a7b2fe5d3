// fragg_map correct MAP.fgm --poses FILE -o OUT.fgm: moves kept scans to corrected poses
// (loop closure) without rebuilding the map.
#include <fmt/format.h>

#include <cstdio>
#include <nlohmann/json.hpp>
#include <string>

#include "cli/commands.h"
#include "cli/map_input.h"
#include "fragg_map/atomic_file.h"
#include "fragg_map/errors.h"
#include "fragg_map/io/pose_file.h"
#include "fragg_map/map.h"

namespace fragg::cli {

namespace {
struct CorrectOptions {
  std::string map, poses, output, backend = "auto";
  bool json = false;
};

void runCorrect(const CorrectOptions& o) {
  if (extensionOf(o.map) != "fgm")
    throw InvalidArgument("correct needs a .fgm map saved with its scans, got '" + o.map + "'");
  if (extensionOf(o.output) != "fgm")
    throw InvalidArgument("output must be a .fgm file, got '" + o.output + "'");
  checkOutputDirectory(o.output);
  { AtomicFile probe(o.output); }  // fail now, not after the correction
  const auto poses = readScanPoses(o.poses);
  Map map = Map::load(o.map, backendFromString(o.backend));
  if (map.scanStore().size() == 0)
    throw InvalidArgument(o.map +
                          " keeps no scans: build it with `fragg_map build --keep-scans` to "
                          "correct poses later");
  const CorrectionStats st = map.correctPoses(poses);  // checks every index and pose first
  map.save(o.output);
  const double ms = st.seconds_total * 1e3;
  if (o.json) {
    nlohmann::json j = {{"output", o.output},
                        {"backend", map.backendName()},
                        {"scans_corrected", st.scans},
                        {"ms_total", ms},
                        {"ms_per_scan", ms / st.scans},
                        {"ms_removal", st.removal.seconds_total * 1e3},
                        {"ms_insertion", st.insertion.seconds_total * 1e3},
                        {"cells_removed", st.removal.cells_updated},
                        {"cells_inserted", st.insertion.cells_updated},
                        {"known_voxels", map.knownVoxelCount()}};
    std::printf("%s\n", j.dump().c_str());
    return;
  }
  std::printf("%s\n", fmt::format("corrected {} of {} kept scans in {:.1f} ms ({:.2f} ms per scan: "
                                  "removal {:.1f} ms, re-insertion {:.1f} ms), backend {}; "
                                  "wrote {}",
                                  st.scans, map.scanStore().size(), ms, ms / st.scans,
                                  st.removal.seconds_total * 1e3, st.insertion.seconds_total * 1e3,
                                  map.backendName(), o.output)
                          .c_str());
}
}  // namespace

void addCorrectCommand(CLI::App& app) {
  auto o = std::make_shared<CorrectOptions>();
  CLI::App* c = app.add_subcommand(
      "correct",
      "Move kept scans to corrected poses (loop closure): each listed scan is removed and "
      "inserted again, no rebuild");
  c->add_option("map", o->map, "Map built with --keep-scans (.fgm)")->required();
  c->add_option("--poses", o->poses,
                "Corrected poses, one per line: scan_index tx ty tz qx qy qz qw (T_map_sensor; "
                "indices as `fragg_map stats --scans` lists them)")
      ->required();
  c->add_option("-o,--output", o->output, "Corrected map to write (.fgm)")->required();
  c->add_option("--backend", o->backend, "auto | cpu | cuda")->capture_default_str();
  c->add_flag("--json", o->json, "Print one JSON object on stdout");
  c->callback([o] { runCorrect(*o); });
}

}  // namespace fragg::cli
