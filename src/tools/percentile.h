// Percentiles of timing samples, for the CLI summary and the benchmark tables.
#pragma once

#include <algorithm>
#include <cmath>
#include <vector>

namespace fragg::tools {

/// The q-quantile (0 <= q <= 1) by the nearest-rank method; 0 for no samples.
inline double percentile(std::vector<double> samples, double q) {
  if (samples.empty()) return 0.0;
  std::sort(samples.begin(), samples.end());
  const size_t rank = static_cast<size_t>(std::ceil(q * samples.size()));
  return samples[std::min(samples.size() - 1, rank == 0 ? 0 : rank - 1)];
}

}  // namespace fragg::tools
