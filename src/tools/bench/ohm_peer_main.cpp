// fragg_map_ohm_bench: fragg's CUDA backend and the peer GPU mapper OHM (csiro-robotics/ohm,
// CUDA GpuMap) on the same scans, resolution and range, in one process on one GPU.
//
// Repeats alternate the two engines (fragg first on even repeats, OHM first on odd ones), each
// on a fresh map over every scan, so that the ratio is taken in one run. A scan is timed from
// the call to its end on the GPU: Map::insert for fragg (sensor-frame points in, the stream
// synchronised), for OHM the rays moved to the map frame on the host, integrateRays and its
// GPU queue finished (both columns printed). Afterwards the maps are compared cell by cell
// (OctoMap's rule: occupied iff log-odds >= 0) with each other and, over the first
// --octomap-scans scans, with OctoMap's.
#include <fmt/format.h>

#include <CLI/CLI.hpp>
#include <chrono>
#include <cstdio>
#include <fstream>
#include <nlohmann/json.hpp>
#include <string>
#include <vector>

#include "bench/ohm_engine.h"
#include "bench/workloads.h"
#include "fragg_map/errors.h"
#include "fragg_map/interop/compare.h"
#include "percentile.h"

#ifdef FRAGG_HAVE_OCTOMAP
#include <octomap/octomap.h>

#include "fragg_map/interop/octomap_insert.h"
#include "fragg_map/interop/octomap_io.h"
#endif

namespace fragg::bench {
namespace {

using tools::percentile;
using Clock = std::chrono::steady_clock;

struct Options {
  std::string workloads, json_path, only;
  size_t workload_scans = 0;
  int repeats = 3, octomap_scans = 3;
  std::string fragg_backend = "cuda";
  OhmOptions ohm;
};

struct Samples {
  std::vector<double> fragg_ms, ohm_ms, ohm_gpu_ms;
  double ohm_pipelined_ms = 0;  ///< mean per scan, one run without waiting after each scan
  double ohm_sync_s = 0;        ///< syncVoxels after the last repeat
  std::string ohm_model;        ///< OHM's occupancy model as used
};

struct Agreement {
  std::string a, b;
  size_t scans = 0;
  MapComparison c;
};

double mean(const std::vector<double>& v) {
  double sum = 0;
  for (double x : v) sum += x;
  return v.empty() ? 0.0 : sum / v.size();
}

MapParams fraggParams(const Workload& w, const std::string& backend = "cuda") {
  MapParams p;
  p.resolution_m = w.resolution_m;
  p.backend = backendFromString(backend);
  p.occupancy.unknown_band = 0.0;  // OctoMap's rule, for the agreement figures
  return p;
}

OhmOptions ohmOptions(const Workload& w, const Options& o) {
  OhmOptions p = o.ohm;
  p.resolution_m = w.resolution_m;
  p.max_range_m = w.max_range_m;
  p.occupancy = fraggParams(w).occupancy;
  size_t most = 0;
  for (const Scan& s : w.scans) most = std::max(most, s.cloud.size());
  p.expected_points = std::max<size_t>(most, 1024);
  return p;
}

double insertTimed(Map& map, const Scan& s, double max_range_m) {
  const auto t0 = Clock::now();
  map.insert(s.cloud, s.T_map_sensor, SensorModel::autoFromCloud(0.0, max_range_m));
  return std::chrono::duration<double, std::milli>(Clock::now() - t0).count();
}

Map runFraggOnce(const Workload& w, const Options& o, size_t count, std::vector<double>* ms) {
  Map map(fraggParams(w, o.fragg_backend));
  for (size_t i = 0; i < count; ++i) {
    const double t = insertTimed(map, w.scans[i], w.max_range_m);
    if (ms) ms->push_back(t);
  }
  return map;
}

/// One OHM run over the first `count` scans; its map is converted only when `keep` is given.
void runOhmOnce(const Workload& w, const Options& o, size_t count, Samples* samples, Map* keep) {
  OhmEngine ohm(ohmOptions(w, o));
  for (size_t i = 0; i < count; ++i) {
    const OhmScanTimes t = ohm.integrate(w.scans[i]);
    if (samples) {
      samples->ohm_ms.push_back(t.ms_total);
      samples->ohm_gpu_ms.push_back(t.ms_gpu);
    }
  }
  if (samples) {
    samples->ohm_sync_s = ohm.syncToHost();
    samples->ohm_model = ohm.describeModel();
  }
  if (keep) *keep = ohm.toMap();
}

/// OHM's throughput when it may overlap scans (GpuMap double-buffers its uploads): one run over
/// every scan without waiting after each, the GPU finished at the end; mean ms per scan.
double ohmPipelinedMs(const Workload& w, const Options& o) {
  OhmEngine ohm(ohmOptions(w, o));
  const auto t0 = Clock::now();
  for (const Scan& scan : w.scans) ohm.integrate(scan, false);
  ohm.finish();
  return std::chrono::duration<double, std::milli>(Clock::now() - t0).count() / w.scans.size();
}

Agreement agreement(const std::string& a, const Map& ma, const std::string& b, const Map& mb,
                    size_t scans) {
  CompareOptions rule;
  rule.octomap_threshold = true;
  return {a, b, scans, compareMaps(ma, mb, rule)};
}

nlohmann::json runWorkload(const Workload& w, const Options& o) {
  const size_t n = w.scans.size();
  if (n == 0) throw InvalidArgument(w.name + ": no scans");
  {  // Warm-up, untimed: CUDA context, OHM's program, first allocations of both engines.
    OhmEngine warm(ohmOptions(w, o));
    warm.integrate(w.scans[0]);
    runFraggOnce(w, o, 1, nullptr);
  }
  Samples s;
  Map fragg_map, ohm_map;
  for (int r = 0; r < o.repeats; ++r) {
    const bool last = r + 1 == o.repeats;
    for (int k = 0; k < 2; ++k) {
      if ((k == 0) == (r % 2 == 0)) {
        Map m = runFraggOnce(w, o, n, &s.fragg_ms);
        if (last) fragg_map = std::move(m);
      } else {
        runOhmOnce(w, o, n, &s, last ? &ohm_map : nullptr);
      }
    }
  }
  s.ohm_pipelined_ms = ohmPipelinedMs(w, o);
  const std::string fragg_name = "fragg-" + o.fragg_backend;
  const std::string ohm_name = o.ohm.cpu ? "ohm-cpu" : "ohm";
  std::vector<Agreement> agree = {agreement(fragg_name, fragg_map, ohm_name, ohm_map, n)};
  const std::string& model = s.ohm_model;
  double octomap_ms = 0;
  size_t n_octo = 0;
#ifdef FRAGG_HAVE_OCTOMAP
  n_octo = std::min<size_t>(n, std::max(0, o.octomap_scans));
  if (n_octo > 0) {
    octomap::OcTree tree(w.resolution_m);  // OctoMap's defaults = fragg's defaults
    std::vector<double> ms;
    for (size_t i = 0; i < n_octo; ++i)
      ms.push_back(insertIntoOcTree(tree, w.scans[i], w.max_range_m) * 1e3);
    octomap_ms = percentile(ms, 0.5);
    const Map octo = fromOcTree(tree);
    const Map fragg_same = runFraggOnce(w, o, n_octo, nullptr);
    Map ohm_same;
    runOhmOnce(w, o, n_octo, nullptr, &ohm_same);
    agree.push_back(agreement(fragg_name, fragg_same, "octomap", octo, n_octo));
    agree.push_back(agreement(ohm_name, ohm_same, "octomap", octo, n_octo));
    agree.push_back(agreement(fragg_name, fragg_same, ohm_name, ohm_same, n_octo));
  }
#endif

  const double fragg_med = percentile(s.fragg_ms, 0.5), ohm_med = percentile(s.ohm_ms, 0.5);
  const double ohm_gpu_med = percentile(s.ohm_gpu_ms, 0.5);
  const std::string range =
      w.max_range_m > 0 ? fmt::format("{:.0f} m", w.max_range_m) : std::string("none");
  std::printf("\n### %s (%.2f m, range %s, %zu scans x %d repeats)\nOHM model: %s\n\n",
              w.name.c_str(), w.resolution_m, range.c_str(), n, o.repeats, model.c_str());
  std::printf("| engine | ms/scan median | p99 | OHM / fragg (median) |\n|---|---|---|---|\n");
  std::printf("| %s (Map::insert) | %.3f | %.3f | 1 |\n", fragg_name.c_str(), fragg_med,
              percentile(s.fragg_ms, 0.99));
  std::printf("| %s (host rays + integrateRays + finish) | %.3f | %.3f | %.2fx |\n",
              ohm_name.c_str(), ohm_med, percentile(s.ohm_ms, 0.99), ohm_med / fragg_med);
  std::printf("| %s (integrateRays + finish only) | %.3f | %.3f | %.2fx |\n", ohm_name.c_str(),
              ohm_gpu_med, percentile(s.ohm_gpu_ms, 0.99), ohm_gpu_med / fragg_med);
  const double fragg_mean = mean(s.fragg_ms);
  std::printf(
      "| %s pipelined (no wait between scans; mean, one run) | %.3f | - | %.2fx of "
      "fragg's mean %.3f |\n",
      ohm_name.c_str(), s.ohm_pipelined_ms, s.ohm_pipelined_ms / fragg_mean, fragg_mean);
  std::printf("\nOHM syncVoxels after the last repeat: %.1f ms", s.ohm_sync_s * 1e3);
  if (n_octo > 0) std::printf("; OctoMap %.1f ms/scan over %zu scans", octomap_ms, n_octo);
  std::printf(
      "\n\n| maps | scans | known in a | known in b | known in both | agree (both "
      "know) | agree (either knows) |\n|---|---|---|---|---|---|---|\n");
  nlohmann::json j_agree = nlohmann::json::array();
  for (const Agreement& a : agree) {
    std::printf("| %s vs %s | %zu | %llu | %llu | %llu | %.4f %% | %.4f %% |\n", a.a.c_str(),
                a.b.c_str(), a.scans, static_cast<unsigned long long>(a.c.known_in_a),
                static_cast<unsigned long long>(a.c.known_in_b),
                static_cast<unsigned long long>(a.c.known_in_both), 100 * a.c.agreementInBoth(),
                100 * a.c.agreementInEither());
    j_agree.push_back({{"a", a.a},
                       {"b", a.b},
                       {"scans", a.scans},
                       {"known_in_a", a.c.known_in_a},
                       {"known_in_b", a.c.known_in_b},
                       {"known_in_both", a.c.known_in_both},
                       {"agree_both", a.c.agreementInBoth()},
                       {"agree_either", a.c.agreementInEither()}});
  }
  std::fflush(stdout);
  return {{"workload", w.name},
          {"resolution_m", w.resolution_m},
          {"max_range_m", w.max_range_m},
          {"scans", n},
          {"repeats", o.repeats},
          {"ohm_model", model},
          {"ohm_gpu_cache_mib", o.ohm.gpu_cache_mib},
          {"fragg_engine", fragg_name},
          {"ohm_engine", ohm_name},
          {"fragg_ms_median", fragg_med},
          {"fragg_ms_p99", percentile(s.fragg_ms, 0.99)},
          {"ohm_ms_median", ohm_med},
          {"ohm_ms_p99", percentile(s.ohm_ms, 0.99)},
          {"ohm_gpu_ms_median", ohm_gpu_med},
          {"ohm_over_fragg", ohm_med / fragg_med},
          {"fragg_ms_mean", fragg_mean},
          {"ohm_pipelined_ms_mean", s.ohm_pipelined_ms},
          {"ohm_sync_ms", s.ohm_sync_s * 1e3},
          {"octomap_ms_median", octomap_ms},
          {"octomap_scans", n_octo},
          {"agreement", j_agree}};
}

}  // namespace
}  // namespace fragg::bench

int main(int argc, char** argv) {
  using namespace fragg;
  using namespace fragg::bench;
  CLI::App app{"fragg_map_ohm_bench: fragg's CUDA backend and OHM's GpuMap on the same scans"};
  Options o;
  app.add_option("--workloads", o.workloads, "Workloads folder (scripts/make_workloads.sh)")
      ->required();
  app.add_option("--workload-scans", o.workload_scans, "Use only the first N scans (0 = all)")
      ->capture_default_str();
  app.add_option("--only", o.only,
                 "Run the workloads whose name contains this (default: W1 lidar360 30 m, "
                 "W1 lidar360 50 m, W2 depth 5 cm)");
  app.add_option("--repeats", o.repeats, "Alternating repeats of each engine")
      ->capture_default_str();
  app.add_option("--octomap-scans", o.octomap_scans,
                 "Scans given to OctoMap for the agreement figures (0: none)")
      ->capture_default_str();
  app.add_option("--ohm-gpu-cache-mib", o.ohm.gpu_cache_mib, "OHM's GPU layer cache")
      ->capture_default_str();
  app.add_option("--ohm-ray-segment-m", o.ohm.ray_segment_m,
                 "OHM's ray segment length (0: its default)")
      ->capture_default_str();
  app.add_option("--fragg-backend", o.fragg_backend, "fragg's backend (cuda; cpu for a check)")
      ->capture_default_str();
  app.add_flag("--ohm-cpu", o.ohm.cpu,
               "OHM's CPU mapper instead of GpuMap: checks the driver and the map conversion on a "
               "machine without a GPU (with --fragg-backend cpu); not a speed figure");
  bool ohm_defaults = false;
  app.add_flag("--ohm-default-model", ohm_defaults,
               "OHM's own occupancy model instead of OctoMap's (hit 0.7, miss 0.4, clamps)");
  app.add_option("--json", o.json_path, "Write the figures as JSON to this file");
  CLI11_PARSE(app, argc, argv);
  o.ohm.matched_model = !ohm_defaults;

  try {
    if (o.repeats < 1) throw InvalidArgument("--repeats must be >= 1");
    backendFromString(o.fragg_backend);  // rejects a typo before any work
    if (o.ohm.gpu_cache_mib == 0) throw InvalidArgument("--ohm-gpu-cache-mib must be > 0");
    if (o.ohm.ray_segment_m < 0) throw InvalidArgument("--ohm-ray-segment-m must be >= 0");
    const WantFn want = [&](const std::string& name) {
      if (!o.only.empty()) return name.find(o.only) != std::string::npos;
      return name == "W1 lidar360 30 m" || name == "W1 lidar360 50 m" || name == "W2 depth 5 cm";
    };
    const std::vector<Workload> workloads = simWorkloads(o.workloads, o.workload_scans, want);
    if (workloads.empty()) throw InvalidArgument("--only '" + o.only + "' matches no workload");
    nlohmann::json out = nlohmann::json::array();
    for (const Workload& w : workloads) out.push_back(runWorkload(w, o));
    if (!o.json_path.empty()) {
      std::ofstream f(o.json_path);
      f << out.dump(2) << "\n";
      if (!f) throw IoError("cannot write " + o.json_path);
    }
  } catch (const std::exception& e) {
    std::fprintf(stderr, "fragg_map_ohm_bench: error: %s\n", e.what());
    return 1;
  }
  return 0;
}
