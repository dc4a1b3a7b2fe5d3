#include "fragg_map/internal/decay.h"

#include <omp.h>

#include <algorithm>
#include <cmath>
#include <vector>

namespace fragg {

int16_t decayStepFx(double log_odds_per_scan) {
  const long fx = std::lround(log_odds_per_scan * kLogOddsScale);
  return static_cast<int16_t>(std::clamp<long>(fx, log_odds_per_scan > 0.0 ? 1 : 0, INT16_MAX));
}

uint64_t decayCells(BlockMap& blocks, const OccupancyModel& model, int16_t step_fx,
                    uint64_t revision, int threads) {
  std::vector<BlockIndex> all;
  all.reserve(blocks.size());
  blocks.forEach([&](BlockIndex i) { all.push_back(i); });
  const long n = static_cast<long>(all.size());
  std::vector<char> masks_changed(all.size(), 0);
  uint64_t decayed = 0;
#pragma omp parallel for num_threads(threads) schedule(dynamic, 64) reduction(+ : decayed)
  for (long j = 0; j < n; ++j) {
    const BlockIndex i = all[static_cast<size_t>(j)];
    Block& block = blocks.block(i);
    BlockStateMasks& masks = blocks.masks(i);
    bool changed = false, occupancy_changed = false, state_changed = false;
    uint64_t masks_differ = 0;
    for (int w = 0; w < kStateMaskWords; ++w) {
      uint64_t occupied_bits = 0, free_bits = 0;
      for (int bit = 0; bit < 64; ++bit) {
        Cell& cell = block.cells[w * 64 + bit];
        const Cell before = cell;
        if (cell.observed() && cell.log_odds_fx != 0) {
          const int v = cell.log_odds_fx;
          cell.log_odds_fx =
              static_cast<int16_t>(v > 0 ? std::max(0, v - step_fx) : std::min(0, v + step_fx));
          changed = true;
          ++decayed;
        }
        const CellState was = model.state(before), is = model.state(cell);
        occupancy_changed |= (was == CellState::kOccupied) != (is == CellState::kOccupied);
        state_changed |= model.stateDiffers(before, cell);
        occupied_bits |= uint64_t{is == CellState::kOccupied} << bit;
        free_bits |= uint64_t{is == CellState::kFree} << bit;
      }
      masks_differ |= (occupied_bits ^ masks.occupied[w]) | (free_bits ^ masks.free[w]);
      masks.occupied[w] = occupied_bits;
      masks.free[w] = free_bits;
    }
    masks_changed[static_cast<size_t>(j)] = masks_differ != 0;
    if (!changed) continue;
    BlockMeta& meta = blocks.meta(i);
    meta.changed_at = revision;
    if (occupancy_changed) meta.occupied_at = revision;
    if (state_changed) meta.state_at = revision;
    // A decayed cell left the lower clamp (a step of at least one unit toward 0).
    meta.free_saturated_at = BlockMeta::kNotSaturated;
  }
  for (long j = 0; j < n; ++j)  // the change log appends: serial
    if (masks_changed[static_cast<size_t>(j)]) blocks.noteMasksChanged(all[j], revision);
  return decayed;
}

}  // namespace fragg
