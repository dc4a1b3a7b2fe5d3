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
/// Every field equal (the same occupancy model: a store's, a copy's).
[[nodiscard]] bool operator==(const OccupancyParams& a, const OccupancyParams& b);

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
  /// Undoes one update of a scan that is being removed (loop closure): takes the endpoint back
  /// from the hit count and subtracts the increment, then applies what any history of
  /// OctoMap's add-then-clamp updates guarantees:
  ///  * a cell with h hits has log-odds <= h * hit (clamping from below only raises values
  ///    that later hits build on from min <= 0);
  ///  * a cell with no hit left holds misses only, so its log-odds is <= miss while it holds
  ///    any: a larger value means no evidence is left and the cell becomes unobserved (it read
  ///    unknown either way, and a later update starts from 0 either way);
  ///  * a hit taken from a cell saturated at max leaves min(max, h * hit): the surplus that
  ///    clamping cut off is assumed to have absorbed it (plain subtraction would turn a wall
  ///    seen by many scans into free space after a few removals).
  /// Exact (the cell ends as if the scan had never been inserted) when neither the cell's
  /// history nor that history without the scan met a clamping bound and its hit count never
  /// saturated; otherwise an estimate. An unobserved cell stays unobserved.
  FRAGG_HD void unapply(Cell& c, bool hit) const {
    if (!c.observed()) return;
    if (hit && c.hits > 0 && c.hits < INT16_MAX) --c.hits;
    const int hit_bound = int{c.hits} * hit_fx;
    int v = int{c.log_odds_fx} - (hit ? hit_fx : miss_fx);
    if (hit && c.log_odds_fx == max_fx) v = max_fx;
    if (v > hit_bound) v = hit_bound;
    if (c.hits == 0 && v > miss_fx) {
      c = Cell();
      return;
    }
    c.log_odds_fx = clampFx(v);
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
  /// Whether readers see the two values of a cell differently: observed or not, or another
  /// state (what BlockMeta::state_at records).
  FRAGG_HD bool stateDiffers(const Cell& a, const Cell& b) const {
    return a.observed() != b.observed() || state(a) != state(b);
  }
};

/// Fixed-point log-odds of probability p, rounded to nearest.
int16_t logOddsFxOf(double p);
/// log(p / (1 - p)).
double logOdds(double p);
/// Probability of a fixed-point log-odds value.
double probabilityOf(int16_t log_odds_fx);

}  // namespace fragg
