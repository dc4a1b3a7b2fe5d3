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

void fillCube(const VoxelKey& lo, int32_t edge, int16_t fx, BlockMap& blocks) {
  const VoxelKey hi{lo.x + edge - 1, lo.y + edge - 1, lo.z + edge - 1};
  const BlockKey b_lo = blockKeyOf(lo);
  const BlockKey b_hi = blockKeyOf(hi);
  for (int32_t bz = b_lo.z; bz <= b_hi.z; ++bz) {
    for (int32_t by = b_lo.y; by <= b_hi.y; ++by) {
      for (int32_t bx = b_lo.x; bx <= b_hi.x; ++bx) {
        Block& block = blocks.block(blocks.findOrCreate(BlockKey{bx, by, bz}));
        const VoxelKey first = voxelKeyOf(BlockKey{bx, by, bz}, 0);
        const int32_t z0 = std::max(lo.z, first.z), z1 = std::min(hi.z, first.z + kBlockMask);
        const int32_t y0 = std::max(lo.y, first.y), y1 = std::min(hi.y, first.y + kBlockMask);
        const int32_t x0 = std::max(lo.x, first.x), x1 = std::min(hi.x, first.x + kBlockMask);
        for (int32_t z = z0; z <= z1; ++z)
          for (int32_t y = y0; y <= y1; ++y)
            for (int32_t x = x0; x <= x1; ++x)
              block.cells[cellIndexOf(VoxelKey{x, y, z})].log_odds_fx = fx;
      }
    }
  }
}

}  // namespace fragg::internal
