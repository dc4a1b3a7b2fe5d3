// fragg_map stats MAP: what a map holds.
#include <fmt/format.h>
#include <sys/stat.h>

#include <cstdio>
#include <nlohmann/json.hpp>
#include <string>

#include "cli/commands.h"
#include "cli/map_input.h"
#include "fragg_map/map.h"

namespace fragg::cli {

namespace {
struct StatsOptions {
  std::string map;
  bool json = false;
  bool list_scans = false;
};

/// The kept scans as `fragg_map correct` names them: index, stamp, T_map_sensor, points.
nlohmann::json keptScans(const Map& map) {
  nlohmann::json list = nlohmann::json::array();
  for (ScanId id : map.scanStore().ids()) {
    const ScanRecord& r = map.scanStore().record(id);
    const Eigen::Quaterniond q(r.T_map_sensor.linear());
    const Eigen::Vector3d t = r.T_map_sensor.translation();
    list.push_back({{"index", id},
                    {"stamp_ns", r.stamp_ns},
                    {"pose", {t.x(), t.y(), t.z(), q.x(), q.y(), q.z(), q.w()}},
                    {"points", r.points},
                    {"sensor", toString(r.model.type)}});
  }
  return list;
}

/// The kept scans as a file `fragg_map correct --poses` reads: a pose line per scan, the rest
/// in comments.
void printScanPoses(const Map& map, const std::string& path) {
  std::printf("# kept scans of %s: scan_index tx ty tz qx qy qz qw (T_map_sensor)\n", path.c_str());
  for (const auto& s : keptScans(map)) {
    const auto& p = s["pose"];
    std::printf("%s\n", fmt::format("# stamp_ns {}, {} points, sensor {}\n{} {:.6f} {:.6f} {:.6f} "
                                    "{:.9f} {:.9f} {:.9f} {:.9f}",
                                    s["stamp_ns"].get<int64_t>(), s["points"].get<uint64_t>(),
                                    s["sensor"].get<std::string>(), s["index"].get<uint64_t>(),
                                    p[0].get<double>(), p[1].get<double>(), p[2].get<double>(),
                                    p[3].get<double>(), p[4].get<double>(), p[5].get<double>(),
                                    p[6].get<double>())
                            .c_str());
  }
}

void runStats(const StatsOptions& o) {
  const Map map = loadMapFile(o.map);
  if (o.list_scans && !o.json) {
    printScanPoses(map, o.map);
    return;
  }
  size_t counts[3] = {0, 0, 0};
  size_t observed = 0;
  map.forEachBlock([&](const BlockKey&, const Block& block) {
    for (const Cell& c : block.cells) {
      if (!c.observed()) continue;
      ++observed;
      ++counts[static_cast<int>(map.state(c))];
    }
  });
  const KeyBounds b = map.bounds();
  const MemoryStats mem = map.memory();
  struct stat st {};
  const long long file_bytes = ::stat(o.map.c_str(), &st) == 0 ? st.st_size : -1;
  const double res = map.resolution();
  const OccupancyParams& occ = map.params().occupancy;
  nlohmann::json bounds = nullptr;
  if (!b.empty) {
    bounds = {{"min_m", {b.min.x * res, b.min.y * res, b.min.z * res}},
              {"max_m", {(b.max.x + 1) * res, (b.max.y + 1) * res, (b.max.z + 1) * res}}};
  }
  if (o.json) {
    nlohmann::json j = {{"map", o.map},
                        {"file_bytes", file_bytes},
                        {"resolution_m", res},
                        {"scans", map.scanCount()},
                        {"kept_scans", map.scanStore().size()},
                        {"blocks", mem.blocks},
                        {"known_voxels", observed},
                        {"occupied", counts[static_cast<int>(CellState::kOccupied)]},
                        {"free", counts[static_cast<int>(CellState::kFree)]},
                        {"unknown_band", counts[static_cast<int>(CellState::kUnknown)]},
                        {"bounds", bounds},
                        {"host_bytes", mem.host_block_bytes},
                        {"occupancy",
                         {{"hit", occ.prob_hit},
                          {"miss", occ.prob_miss},
                          {"clamp_min", occ.clamp_min},
                          {"clamp_max", occ.clamp_max},
                          {"unknown_band", occ.unknown_band}}}};
    if (o.list_scans) j["scan_list"] = keptScans(map);
    std::printf("%s\n", j.dump().c_str());
    return;
  }
  std::printf("%s", fmt::format("map          {}\n"
                                "file         {} bytes\n"
                                "resolution   {} m\n"
                                "scans        {}\n"
                                "blocks       {} (8^3 cells each)\n"
                                "known voxels {} (occupied {}, free {}, in the unknown band {})\n",
                                o.map, file_bytes, res, map.scanCount(), mem.blocks, observed,
                                counts[2], counts[1], counts[0])
                        .c_str());
  if (!b.empty)
    std::printf("%s", fmt::format("bounds       [{:.2f}, {:.2f}, {:.2f}] .. [{:.2f}, {:.2f}, "
                                  "{:.2f}] m\n",
                                  b.min.x * res, b.min.y * res, b.min.z * res, (b.max.x + 1) * res,
                                  (b.max.y + 1) * res, (b.max.z + 1) * res)
                          .c_str());
  std::printf("%s", fmt::format("memory       {:.1f} MiB in host blocks\n"
                                "occupancy    hit {} miss {} clamp [{}, {}] unknown band {}\n",
                                mem.host_block_bytes / 1048576.0, occ.prob_hit, occ.prob_miss,
                                occ.clamp_min, occ.clamp_max, occ.unknown_band)
                        .c_str());
  std::printf("kept scans   %zu%s\n", map.scanStore().size(),
              map.scanStore().size() ? " (fragg_map correct can move them; --scans lists them)"
                                     : " (built without --keep-scans: poses cannot be corrected)");
}
}  // namespace

void addStatsCommand(CLI::App& app) {
  auto o = std::make_shared<StatsOptions>();
  CLI::App* c = app.add_subcommand("stats", "Print what a map holds (.fgm or .bt)");
  c->add_option("map", o->map, "Map file")->required();
  c->add_flag("--json", o->json, "Print one JSON object on stdout");
  c->add_flag("--scans", o->list_scans,
              "Print only the kept scans, as the file `fragg_map correct --poses` reads (index "
              "and pose per line; stamp, points and sensor in comments); with --json, add them "
              "as scan_list");
  c->callback([o] { runStats(*o); });
}

}  // namespace fragg::cli
