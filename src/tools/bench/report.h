// The benchmark's results: one row per (workload, engine), so that another backend is one more
// row per workload; printed as a markdown table and written as JSON.
#pragma once

#include <cstdint>
#include <nlohmann/json.hpp>
#include <optional>
#include <string>
#include <vector>

namespace fragg::bench {

struct EngineRow {
  std::string engine;  ///< "fragg-cpu", "fragg-cuda", "octomap"
  size_t scans_timed = 0;
  int repeats = 1;
  double ms_median = 0, ms_p99 = 0;
  double visits_per_s = 0;  ///< fragg only
  double bytes_per_known_voxel = 0;
  size_t known_voxels = 0;
  std::optional<double> ms_median_same_scans;  ///< over the scans OctoMap was given
  std::optional<double> speedup;               ///< OctoMap median / this, same scans
  std::optional<double> agree_both, agree_either;
  std::optional<double> speedup_vs_cpu;              ///< fragg-cpu median / this, same run
  double device_mib = 0, device_estimate_mib = 0;    ///< CUDA: GPU memory, formula (1)
  uint64_t blocks_uploaded = 0, blocks_evicted = 0;  ///< CUDA, last run
  /// Mean ms per scan of each stage of Map::insert (last run): cull, prepare, residency,
  /// raycast, apply, total.
  std::vector<std::pair<std::string, double>> stages_ms;
};

struct WorkloadResult {
  std::string name, group;
  double resolution_m = 0, max_range_m = -1;
  size_t scans = 0, points_per_scan = 0;
  std::vector<EngineRow> rows;
};

std::string markdownHeader();
std::string markdownRows(const WorkloadResult& r);
nlohmann::json toJson(const WorkloadResult& r);

}  // namespace fragg::bench
