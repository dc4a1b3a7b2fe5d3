// The benchmark's workloads: real scans (../shared/data/real), the in-process synthetic LiDAR,
// and the simulator's standard workloads (scripts/make_workloads.sh): W1 lidar360 at 30 and
// 50 m, W2 depth at 2, 5, 10 and 20 cm.
#pragma once

#include <functional>
#include <string>
#include <vector>

#include "fragg_map/io/dataset.h"

namespace fragg::bench {

struct Workload {
  std::string name;
  std::vector<Scan> scans;
  double resolution_m = 0.05;
  double max_range_m = -1.0;  ///< <= 0: no limit
  std::string group;          ///< "real", "synthetic", "W1", "W2"
};

using WantFn = std::function<bool(const std::string&)>;

std::vector<Workload> realWorkloads(const std::string& data_dir, const WantFn& want);
std::vector<Workload> syntheticWorkloads(int scans, double resolution_m, const WantFn& want);
/// W1 from DIR/w1_lidar360 (first max_scans scans; 0 = all), W2 from DIR/w2_depth; a missing
/// folder is an IoError naming scripts/make_workloads.sh.
std::vector<Workload> simWorkloads(const std::string& dir, size_t max_scans, const WantFn& want);

}  // namespace fragg::bench
