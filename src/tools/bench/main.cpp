// fragg_map_bench: fragg (one row per backend) and OctoMap on the same scans in one process.
//
// Prints a markdown table, one row per (workload, engine), and with --json FILE the same
// figures as JSON: ms/scan median and p99, voxel visits per second, the speed ratio against
// OctoMap over the same scans, bytes per known voxel and cell agreement with OctoMap.
#include <fmt/format.h>

#include <CLI/CLI.hpp>
#include <algorithm>
#include <cstdio>
#include <fstream>
#include <nlohmann/json.hpp>
#include <string>
#include <vector>

#include "bench/engines.h"
#include "bench/report.h"
#include "bench/workloads.h"
#include "fragg_map/errors.h"
#include "percentile.h"

namespace fragg::bench {
namespace {

using tools::percentile;

struct Options {
  std::string data = "../shared/data/real", workloads, json_path, only;
  std::vector<std::string> backends = {"cpu"};
  int synthetic_scans = 20, octomap_scans = 3, repeats = 3, threads = 0;
  size_t workload_scans = 0;
  size_t slowest = 0;  ///< print this many slowest scans of each fragg run
  double synthetic_res = 0.05;
  bool no_real = false;
};

/// The `n` slowest scans of a run (all repeats): what the p99 is made of.
void printSlowest(const Workload& w, const std::string& engine, const Figures& f, size_t n) {
  std::vector<size_t> order(f.ms.size());
  for (size_t i = 0; i < order.size(); ++i) order[i] = i;
  n = std::min(n, order.size());
  std::partial_sort(order.begin(), order.begin() + n, order.end(),
                    [&](size_t a, size_t b) { return f.ms[a] > f.ms[b]; });
  const size_t per_repeat = w.scans.empty() ? 1 : w.scans.size();
  for (size_t k = 0; k < n; ++k) {
    const size_t i = order[k];
    const InsertStats& s = f.scan_stats.at(i);
    std::fprintf(stderr,
                 "[slow scan] %s %s: repeat %zu scan %zu: %.2f ms (cull %.2f prepare %.2f "
                 "residency %.2f raycast %.2f apply %.2f) blocks created %llu uploaded %llu "
                 "evicted %llu touched %llu, visits %.1f M\n",
                 w.name.c_str(), engine.c_str(), i / per_repeat, i % per_repeat, f.ms[i],
                 s.seconds_cull * 1e3, s.seconds_prepare * 1e3, s.seconds_residency * 1e3,
                 s.seconds_raycast * 1e3, s.seconds_apply * 1e3,
                 static_cast<unsigned long long>(s.blocks_created),
                 static_cast<unsigned long long>(s.blocks_uploaded),
                 static_cast<unsigned long long>(s.blocks_evicted),
                 static_cast<unsigned long long>(s.blocks_touched), s.voxel_visits / 1e6);
  }
}

/// The p99 without each repeat's first scan (the one that creates a new map, with its device
/// pool and pinned chunks): the steady state a running robot sees, beside the table's p99 of
/// every scan.
void printSteadyP99(const Workload& w, const std::string& engine, const Figures& f) {
  const size_t per_repeat = w.scans.empty() ? 1 : w.scans.size();
  std::vector<double> steady;
  for (size_t i = 0; i < f.ms.size(); ++i)
    if (i % per_repeat != 0) steady.push_back(f.ms[i]);
  if (steady.empty()) return;
  const double median = percentile(steady, 0.5), p99 = percentile(steady, 0.99);
  std::fprintf(stderr,
               "[p99 without each map's first scan] %s %s: median %.2f ms, p99 %.2f ms (%.2fx), "
               "%zu scans\n",
               w.name.c_str(), engine.c_str(), median, p99, median > 0 ? p99 / median : 0.0,
               steady.size());
  // Each stage over the same scans: which one the slow scans' time comes from.
  const std::pair<const char*, double InsertStats::*> stages[] = {
      {"cull", &InsertStats::seconds_cull},
      {"prepare", &InsertStats::seconds_prepare},
      {"residency", &InsertStats::seconds_residency},
      {"raycast", &InsertStats::seconds_raycast},
      {"apply", &InsertStats::seconds_apply}};
  std::string line;
  for (const auto& [name, field] : stages) {
    std::vector<double> ms;
    for (size_t i = 0; i < f.scan_stats.size(); ++i)
      if (i % per_repeat != 0) ms.push_back(f.scan_stats[i].*field * 1e3);
    line += fmt::format(" {} {:.2f}/{:.2f}/{:.2f}", name, percentile(ms, 0.5), percentile(ms, 0.99),
                        *std::max_element(ms.begin(), ms.end()));
  }
  std::fprintf(stderr, "[stage ms median/p99/max without first scans] %s %s:%s\n", w.name.c_str(),
               engine.c_str(), line.c_str());
}

WorkloadResult runWorkload(const Workload& w, const Options& o) {
  WorkloadResult r;
  r.name = w.name;
  r.group = w.group;
  r.resolution_m = w.resolution_m;
  r.max_range_m = w.max_range_m;
  r.scans = w.scans.size();
  size_t points = 0;
  for (const Scan& s : w.scans) points += s.cloud.size();
  r.points_per_scan = w.scans.empty() ? 0 : points / w.scans.size();
  const size_t n_octo = std::min<size_t>(w.scans.size(), std::max(0, o.octomap_scans));
#ifdef FRAGG_HAVE_OCTOMAP
  const bool with_octomap = n_octo > 0;
#else
  const bool with_octomap = false;
#endif
  std::vector<Map> same_maps;
  std::vector<double> same_medians;
  for (const std::string& name : o.backends) {
    const Figures all = runFragg(w, name, w.scans.size(), o.repeats, o.threads, nullptr);
    EngineRow row;
    row.engine = std::string("fragg-") + name;
    row.device_mib = all.device_bytes / 1048576.0;
    row.device_estimate_mib = all.device_estimate_bytes / 1048576.0;
    row.blocks_uploaded = all.totals.blocks_uploaded;
    row.blocks_evicted = all.totals.blocks_evicted;
    const InsertStats& t = all.totals;
    const double per_scan = w.scans.empty() ? 0.0 : 1e3 / w.scans.size();
    row.stages_ms = {
        {"cull", t.seconds_cull * per_scan},           {"prepare", t.seconds_prepare * per_scan},
        {"residency", t.seconds_residency * per_scan}, {"raycast", t.seconds_raycast * per_scan},
        {"apply", t.seconds_apply * per_scan},         {"total", t.seconds_total * per_scan}};
    std::string line;
    for (const auto& [stage, ms] : row.stages_ms) line += fmt::format(" {} {:.3f}", stage, ms);
    std::fprintf(stderr, "[stages ms/scan] %s %s:%s\n", w.name.c_str(), row.engine.c_str(),
                 line.c_str());
    std::fprintf(stderr, "[traversal per scan] %s %s: %.2f M visits\n", w.name.c_str(),
                 row.engine.c_str(), t.voxel_visits * per_scan / 1e9);
    printSlowest(w, row.engine, all, o.slowest);
    printSteadyP99(w, row.engine, all);
    row.scans_timed = w.scans.size();
    row.repeats = o.repeats;
    row.ms_median = percentile(all.ms, 0.5);
    row.ms_p99 = percentile(all.ms, 0.99);
    row.visits_per_s = all.seconds > 0 ? all.visits / all.seconds : 0;
    row.bytes_per_known_voxel = all.known ? double(all.bytes) / all.known : 0;
    row.known_voxels = all.known;
    if (with_octomap) {
      Map same;
      const Figures f = runFragg(w, name, n_octo, o.repeats, o.threads, &same);
      row.ms_median_same_scans = percentile(f.ms, 0.5);
      same_maps.push_back(std::move(same));
    }
    r.rows.push_back(row);
  }
  // Against the CPU backend (all host cores) in the same run, when it has a row.
  for (const EngineRow& cpu : r.rows)
    if (cpu.engine == "fragg-cpu")
      for (EngineRow& row : r.rows) row.speedup_vs_cpu = cpu.ms_median / row.ms_median;
#ifdef FRAGG_HAVE_OCTOMAP
  if (with_octomap) {
    const OctomapRun octo = runOctomap(w, n_octo);
    EngineRow row;
    row.engine = "octomap";
    row.scans_timed = n_octo;
    row.ms_median = percentile(octo.figures.ms, 0.5);
    row.ms_p99 = percentile(octo.figures.ms, 0.99);
    row.bytes_per_known_voxel =
        octo.figures.known ? double(octo.figures.bytes) / octo.figures.known : 0;
    row.known_voxels = octo.figures.known;
    for (size_t i = 0; i < same_maps.size(); ++i) {
      EngineRow& fr = r.rows[i];
      fr.speedup = row.ms_median / *fr.ms_median_same_scans;
      const auto [both, either] = agreementWithOctomap(same_maps[i], octo.map);
      fr.agree_both = both;
      fr.agree_either = either;
    }
    r.rows.push_back(row);
  }
#endif
  return r;
}

}  // namespace
}  // namespace fragg::bench

int main(int argc, char** argv) {
  using namespace fragg;
  using namespace fragg::bench;
  CLI::App app{"fragg_map_bench: fragg (one row per backend) against OctoMap on the same scans"};
  Options o;
  app.add_option("--data", o.data, "Real data folder (shared/data/real)")->capture_default_str();
  app.add_flag("--no-real", o.no_real, "Skip the real-data workloads");
  app.add_option("--workloads", o.workloads,
                 "Simulated workloads folder (scripts/make_workloads.sh): runs W1 lidar360 at "
                 "30 and 50 m and W2 depth at 2, 5, 10 and 20 cm");
  app.add_option("--workload-scans", o.workload_scans,
                 "Use only the first N scans of W1 and W2 (0 = all)")
      ->capture_default_str();
  app.add_option("--backends", o.backends,
                 "fragg engines, one row each: cpu, cuda, and CUDA ablations cuda+pageable, "
                 "cuda+plain-loads, cuda+no-coherence, cuda+bresenham, cpu+octomap-raycast")
      ->capture_default_str();
  app.add_option("--synthetic-scans", o.synthetic_scans, "Synthetic 180k-point scans")
      ->capture_default_str();
  app.add_option("--octomap-scans", o.octomap_scans,
                 "Scans per workload given to OctoMap (it is slow); the speed-up compares fragg "
                 "on the same scans (0: no OctoMap)")
      ->capture_default_str();
  app.add_option("--repeats", o.repeats, "Repetitions of each fragg run")->capture_default_str();
  app.add_option("--threads", o.threads, "CPU threads for fragg (0 = every core)");
  app.add_option("--synthetic-resolution", o.synthetic_res, "Resolution of the synthetic runs")
      ->capture_default_str();
  app.add_option("--only", o.only, "Run only workloads whose name contains this");
  app.add_option("--slowest", o.slowest,
                 "Print the N slowest scans of each fragg run with their stages and blocks");
  app.add_option("--json", o.json_path, "Write the figures as JSON to this file");
  CLI11_PARSE(app, argc, argv);

  try {
    if (o.repeats < 1) throw InvalidArgument("--repeats must be >= 1");
    for (const std::string& b : o.backends) engineParams(b, MapParams());  // reject typos now
    const WantFn want = [&](const std::string& n) {
      return o.only.empty() || n.find(o.only) != std::string::npos;
    };
    std::vector<Workload> workloads;
    if (!o.no_real) workloads = realWorkloads(o.data, want);
    for (Workload& w : syntheticWorkloads(o.synthetic_scans, o.synthetic_res, want))
      workloads.push_back(std::move(w));
    if (!o.workloads.empty())
      for (Workload& w : simWorkloads(o.workloads, o.workload_scans, want))
        workloads.push_back(std::move(w));

    nlohmann::json out = nlohmann::json::array();
    std::printf("%s", markdownHeader().c_str());
    for (const Workload& w : workloads) {
      const WorkloadResult r = runWorkload(w, o);
      std::printf("%s", markdownRows(r).c_str());
      std::fflush(stdout);
      out.push_back(toJson(r));
    }
    if (!o.json_path.empty()) {
      std::ofstream f(o.json_path);
      f << out.dump(2) << "\n";
      if (!f) throw IoError("cannot write " + o.json_path);
    }
  } catch (const std::exception& e) {
    std::fprintf(stderr, "fragg_map_bench: error: %s\n", e.what());
    return 1;
  }
  return 0;
}
