// Occupancy model: OctoMap's log-odds update in fixed point, plus the paper's unknown band.
#pragma once

#include <cstdint>

#include "fragg_map/cell.h"
#include "fragg_map/hd.h"

namespace fragg {

enum class CellState : uint8_t { kUnknown = 0, kFree = 1, kOccupied = 2 };

const char* toString(CellState s);

/// Probabilities as users give them (OctoMap's defaults).
struct OccupancyParams {
  double prob_hit = 0.7;
  double prob_miss = 0.4;
  double clamp_min = 0.12;
  double clamp_max = 0.97;
  /// Cells with |p - 0.5| <= unknown_band are reported unknown (paper: 0.05).
  double unknown_band = 0.05;

  /// Throws InvalidArgument naming the bad field.
  void validate() const;
};

/// The same model in fixed point, as the update kernels use it. Built on the host by
/// `OccupancyModel::fromParams`; plain data so it can be copied to the device.
struct OccupancyModel {
  int16_t hit_fx = 0;
  int16_t miss_fx = 0;
  int16_t min_fx = 0;
  int16_t max_fx = 0;
  /// log_odds_fx > occupied_above_fx  <=>  p > 0.5 + band
  int16_t occupied_above_fx = 0;
  /// log_odds_fx < free_below_fx  <=>  p < 0.5 - band
  int16_t free_below_fx = 0;

  static OccupancyModel fromParams(const OccupancyParams& p);

  FRAGG_HD int16_t clampFx(int v) const {
    return static_cast<int16_t>(v < min_fx ? min_fx : (v > max_fx ? max_fx : v));
  }
  /// Log-odds after one update (hit or miss) of a cell, OctoMap-style: add, then clamp.
  FRAGG_HD int16_t updated(int16_t log_odds_fx, bool hit) const {
    const int base = log_odds_fx == kUnobservedLogOdds ? 0 : log_odds_fx;
    return clampFx(base + (hit ? hit_fx : miss_fx));
  }
  /// Applies one update to a cell: log-odds and saturating hit count.
  FRAGG_HD void apply(Cell& c, bool hit) const {
    c.log_odds_fx = updated(c.log_odds_fx, hit);
    if (hit && c.hits < INT16_MAX) ++c.hits;
  }
  /// Undoes one update of a scan that is being removed (loop closure): subtracts the
  /// increment, clamps, and takes the endpoint back from the hit count. A cell left with no hit
  /// and a log-odds >= 0 holds no evidence any more (only misses can remain without hits, and
  /// they sum below 0) and becomes unobserved: its state was unknown either way, and a later
  /// update starts from 0 either way. Exact (the cell ends as if the scan had never been
  /// inserted) as long as neither that cell's history nor the history without the scan met a
  /// clamping bound, and its hit count never saturated. An unobserved cell stays so.
  FRAGG_HD void unapply(Cell& c, bool hit) const {
    if (!c.observed()) return;
    if (hit && c.hits > 0 && c.hits < INT16_MAX) --c.hits;
    const int16_t v = clampFx(int{c.log_odds_fx} - (hit ? hit_fx : miss_fx));
    if (c.hits == 0 && v >= 0) {
      c = Cell();
      return;
    }
    c.log_odds_fx = v;
  }
  /// apply() or unapply().
  FRAGG_HD void update(Cell& c, bool hit, bool remove) const {
    if (remove)
      unapply(c, hit);
    else
      apply(c, hit);
  }
  FRAGG_HD CellState state(const Cell& c) const {
    if (!c.observed()) return CellState::kUnknown;
    if (c.log_odds_fx > occupied_above_fx) return CellState::kOccupied;
    if (c.log_odds_fx < free_below_fx) return CellState::kFree;
    return CellState::kUnknown;
  }
};

/// Fixed-point log-odds of probability p, rounded to nearest.
int16_t logOddsFxOf(double p);
/// log(p / (1 - p)).
double logOdds(double p);
/// Probability of a fixed-point log-odds value.
double probabilityOf(int16_t log_odds_fx);

}  // namespace fragg
