#include "fragg_map/occupancy.h"

#include <cmath>
#include <string>

#include "fragg_map/errors.h"

namespace fragg {

const char* toString(CellState s) {
  switch (s) {
    case CellState::kFree:
      return "free";
    case CellState::kOccupied:
      return "occupied";
    case CellState::kUnknown:
      break;
  }
  return "unknown";
}

double logOdds(double p) { return std::log(p / (1.0 - p)); }

int16_t logOddsFxOf(double p) {
  const double v = std::round(logOdds(p) * kLogOddsScale);
  // Keep clear of kUnobservedLogOdds, which marks cells that were never updated.
  const double lo = static_cast<double>(kUnobservedLogOdds) + 1.0;
  return static_cast<int16_t>(v < lo ? lo : (v > INT16_MAX ? INT16_MAX : v));
}

double probabilityOf(int16_t log_odds_fx) {
  return 1.0 - 1.0 / (1.0 + std::exp(static_cast<double>(log_odds_fx) / kLogOddsScale));
}

namespace {
void requireProbability(double p, const char* name) {
  if (!std::isfinite(p) || p <= 0.0 || p >= 1.0)
    throw InvalidArgument(std::string(name) + " must be a probability in (0, 1), got " +
                          std::to_string(p));
}
}  // namespace

// Messages name the fields as MapParams holds them (occupancy.*); front ends rename them.
bool operator==(const OccupancyParams& a, const OccupancyParams& b) {
  return a.prob_hit == b.prob_hit && a.prob_miss == b.prob_miss && a.clamp_min == b.clamp_min &&
         a.clamp_max == b.clamp_max && a.unknown_band == b.unknown_band;
}

void OccupancyParams::validate() const {
  requireProbability(prob_hit, "occupancy.prob_hit");
  requireProbability(prob_miss, "occupancy.prob_miss");
  requireProbability(clamp_min, "occupancy.clamp_min");
  requireProbability(clamp_max, "occupancy.clamp_max");
  if (prob_hit <= 0.5)
    throw InvalidArgument("occupancy.prob_hit must be > 0.5, got " + std::to_string(prob_hit));
  if (prob_miss >= 0.5)
    throw InvalidArgument("occupancy.prob_miss must be < 0.5, got " + std::to_string(prob_miss));
  if (clamp_min >= clamp_max)
    throw InvalidArgument("occupancy.clamp_min must be below occupancy.clamp_max");
  if (!std::isfinite(unknown_band) || unknown_band < 0.0 || unknown_band >= 0.5)
    throw InvalidArgument("occupancy.unknown_band must be in [0, 0.5), got " +
                          std::to_string(unknown_band));
  // Fixed point: log-odds of the clamping range must fit int16 at 1/1024 steps (|l| < 32).
  if (std::fabs(logOdds(clamp_min)) * kLogOddsScale >= 32000)
    throw InvalidArgument("occupancy.clamp_min must lie within (1e-13, 1 - 1e-13)");
  if (std::fabs(logOdds(clamp_max)) * kLogOddsScale >= 32000)
    throw InvalidArgument("occupancy.clamp_max must lie within (1e-13, 1 - 1e-13)");
}

OccupancyModel OccupancyModel::fromParams(const OccupancyParams& p) {
  p.validate();
  OccupancyModel m;
  m.hit_fx = logOddsFxOf(p.prob_hit);
  m.miss_fx = logOddsFxOf(p.prob_miss);
  m.min_fx = logOddsFxOf(p.clamp_min);
  m.max_fx = logOddsFxOf(p.clamp_max);
  // Integer thresholds equivalent to the real-valued band: l > x  <=>  l > floor(x).
  m.occupied_above_fx =
      static_cast<int16_t>(std::floor(logOdds(0.5 + p.unknown_band) * kLogOddsScale));
  m.free_below_fx = static_cast<int16_t>(std::ceil(logOdds(0.5 - p.unknown_band) * kLogOddsScale));
  if (p.unknown_band == 0.0) {
    m.occupied_above_fx = 0;  // OctoMap: occupied iff p > 0.5
    m.free_below_fx = 1;      // every other observed cell is free
  }
  return m;
}

}  // namespace fragg
