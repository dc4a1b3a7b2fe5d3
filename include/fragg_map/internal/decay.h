// Forgetting (MapParams::dynamic.decay_log_odds_per_scan): the map-wide pass the CPU backend
// runs after each integrated scan (DESIGN §12).
#pragma once

#include <cstdint>

#include "fragg_map/block_map.h"
#include "fragg_map/occupancy.h"

namespace fragg {

/// The fixed-point step of `log_odds_per_scan` (rounded to 1/kLogOddsScale; at least one unit
/// for any positive rate, so that a small rate still decays).
[[nodiscard]] int16_t decayStepFx(double log_odds_per_scan);

/// Moves every observed cell of `blocks` `step_fx` (> 0) toward log-odds 0, stopping at 0
/// (hit counts and unobserved cells are left as they are), and keeps what the update keeps in
/// step: state masks, changed_at / occupied_at / state_at / masks_at at `revision` where they
/// changed, the change log, free_saturated_at. Returns the cells changed; `threads` workers.
uint64_t decayCells(BlockMap& blocks, const OccupancyModel& model, int16_t step_fx,
                    uint64_t revision, int threads);

}  // namespace fragg
