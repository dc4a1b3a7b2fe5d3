#include "fragg_map/interop/compare.h"

#include <fmt/format.h>

#include <algorithm>
#include <cmath>
#include <limits>

#include "fragg_map/errors.h"

namespace fragg {
namespace {

CellState stateOf(const OccupancyModel& model, const Cell& cell, bool octomap_threshold) {
  if (!cell.observed()) return CellState::kUnknown;
  if (octomap_threshold) return cell.log_odds_fx >= 0 ? CellState::kOccupied : CellState::kFree;
  return model.state(cell);
}

bool known(CellState s) { return s != CellState::kUnknown; }

void tally(CellState sa, CellState sb, MapComparison& result) {
  ++result.confusion[static_cast<int>(sa)][static_cast<int>(sb)];
  result.known_in_a += known(sa);
  result.known_in_b += known(sb);
  if (known(sa) && known(sb)) ++result.known_in_both;
  if (known(sa) || known(sb)) ++result.known_in_either;
  if (known(sa) && sa == sb) ++result.agreeing;
}

double ratio(uint64_t num, uint64_t den) {
  return den == 0 ? std::numeric_limits<double>::quiet_NaN()
                  : static_cast<double>(num) / static_cast<double>(den);
}

}  // namespace

double MapComparison::agreementInBoth() const { return ratio(agreeing, known_in_both); }
double MapComparison::agreementInEither() const { return ratio(agreeing, known_in_either); }

MapComparison compareMaps(const Map& a, const Map& b, const CompareOptions& options) {
  const double ra = a.resolution(), rb = b.resolution();
  if (!(std::abs(ra - rb) <= 1e-5 * std::max(ra, rb)))
    throw InvalidArgument(
        fmt::format("cannot compare maps of different resolutions ({} m and {} m)", ra, rb));
  MapComparison result;
  result.octomap_threshold = options.octomap_threshold;
  const bool octo = options.octomap_threshold;
  const BlockView blocks_a = a.blockView();
  const BlockView blocks_b = b.blockView();
  const Cell unobserved;

  // Blocks of a, against b's block at the same key (or unobserved space).
  blocks_a.forEach([&](const BlockKey& key, const Block& block_a) {
    const Block* block_b = blocks_b.findBlock(key);
    for (int i = 0; i < kCellsPerBlock; ++i) {
      const Cell& ca = block_a.cells[i];
      const Cell& cb = block_b ? block_b->cells[i] : unobserved;
      if (!ca.observed() && !cb.observed()) continue;
      tally(stateOf(a.model(), ca, octo), stateOf(b.model(), cb, octo), result);
    }
  });
  // Blocks only b has.
  blocks_b.forEach([&](const BlockKey& key, const Block& block_b) {
    if (blocks_a.findBlock(key)) return;
    for (int i = 0; i < kCellsPerBlock; ++i) {
      const Cell& cb = block_b.cells[i];
      if (!cb.observed()) continue;
      tally(CellState::kUnknown, stateOf(b.model(), cb, octo), result);
    }
  });
  return result;
}

}  // namespace fragg
