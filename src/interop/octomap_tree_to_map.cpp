#include "octomap_tree_to_map.h"

#include <algorithm>

namespace fragg::internal {

MapParams mapParamsOfTree(double resolution_m, double prob_hit, double prob_miss, double clamp_min,
                          double clamp_max, const std::string& source) {
  MapParams params;
  params.resolution_m = resolution_m;
  params.occupancy.prob_hit = prob_hit;
  params.occupancy.prob_miss = prob_miss;
  params.occupancy.clamp_min = clamp_min;
  params.occupancy.clamp_max = clamp_max;
  try {
    params.validate();
  } catch (const InvalidArgument& e) {
    throw IoError(fmt::format("{}: unusable OctoMap parameters: {}", source, e.what()));
  }
  return params;
}

int16_t logOddsFxOfNode(float log_odds, const std::string& source) {
  if (!std::isfinite(log_odds))
    throw IoError(
        fmt::format("{}: corrupt OctoMap file: a node holds log-odds {}", source, log_odds));
  const double fx = std::round(static_cast<double>(log_odds) * kLogOddsScale);
  return static_cast<int16_t>(
      std::clamp(fx, static_cast<double>(kUnobservedLogOdds) + 1, static_cast<double>(INT16_MAX)));
}

}  // namespace fragg::internal
