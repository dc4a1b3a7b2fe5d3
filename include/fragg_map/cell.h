// The 4-byte cell and the 2 KiB block (8^3 cells).
#pragma once

#include <cstdint>
#include <limits>

#include "fragg_map/hd.h"
#include "fragg_map/key.h"

namespace fragg {

/// Log-odds are stored in fixed point: value = log_odds_fx / kLogOddsScale.
constexpr int kLogOddsScale = 1024;
/// log_odds_fx of a cell that was never updated (outside any clamping range).
constexpr int16_t kUnobservedLogOdds = INT16_MIN;

struct Cell {
  int16_t hits = 0;                          ///< saturating count of endpoints in the cell
  int16_t log_odds_fx = kUnobservedLogOdds;  ///< fixed-point log-odds, 1/1024 units

  FRAGG_HD bool observed() const { return log_odds_fx != kUnobservedLogOdds; }
};
static_assert(sizeof(Cell) == 4, "a cell is 4 bytes");

struct Block {
  Cell cells[kCellsPerBlock];
};
static_assert(sizeof(Block) == 2048, "a block is 2 KiB");

}  // namespace fragg
