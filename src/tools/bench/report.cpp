#include "bench/report.h"

#include <fmt/format.h>

namespace fragg::bench {

std::string markdownHeader() {
  return "| workload | res m | range m | scans | pts/scan | engine | scans timed | ms/scan median "
         "| "
         "p99 | voxel visits/s | B/voxel | speed-up vs OctoMap | agree (both know) | agree "
         "(either knows) |\n|---|---|---|---|---|---|---|---|---|---|---|---|---|---|\n";
}

std::string markdownRows(const WorkloadResult& r) {
  auto opt = [](const std::optional<double>& v, const char* f, double scale = 1.0) {
    return v ? fmt::format(fmt::runtime(f), *v * scale) : std::string("-");
  };
  std::string out;
  for (const EngineRow& e : r.rows) {
    out += fmt::format(
        "| {} | {:.2f} | {} | {} | {} | {} | {} x {} | {:.1f} | {:.1f} | {} | {:.1f} | {} | {} | "
        "{} |\n",
        r.name, r.resolution_m, r.max_range_m > 0 ? fmt::format("{:.0f}", r.max_range_m) : "none",
        r.scans, r.points_per_scan, e.engine, e.scans_timed, e.repeats, e.ms_median, e.ms_p99,
        e.visits_per_s > 0 ? fmt::format("{:.3g}", e.visits_per_s) : "-", e.bytes_per_known_voxel,
        opt(e.speedup, "{:.1f}x"), opt(e.agree_both, "{:.4f} %", 100),
        opt(e.agree_either, "{:.4f} %", 100));
  }
  return out;
}

nlohmann::json toJson(const WorkloadResult& r) {
  nlohmann::json rows = nlohmann::json::array();
  for (const EngineRow& e : r.rows) {
    nlohmann::json j = {{"engine", e.engine},
                        {"scans_timed", e.scans_timed},
                        {"repeats", e.repeats},
                        {"ms_median", e.ms_median},
                        {"ms_p99", e.ms_p99},
                        {"bytes_per_known_voxel", e.bytes_per_known_voxel},
                        {"known_voxels", e.known_voxels}};
    if (e.visits_per_s > 0) j["visits_per_s"] = e.visits_per_s;
    if (e.ms_median_same_scans) j["ms_median_same_scans"] = *e.ms_median_same_scans;
    if (e.speedup) j["speedup_vs_octomap"] = *e.speedup;
    if (e.agree_both) j["agreement_both"] = *e.agree_both;
    if (e.agree_either) j["agreement_either"] = *e.agree_either;
    rows.push_back(j);
  }
  return {{"workload", r.name},
          {"group", r.group},
          {"resolution_m", r.resolution_m},
          {"max_range_m", r.max_range_m},
          {"scans", r.scans},
          {"points_per_scan", r.points_per_scan},
          {"results", rows}};
}

}  // namespace fragg::bench
