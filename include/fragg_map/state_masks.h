// Cell-state masks of a block (DESIGN §12): the map's second layer. Bit c of a mask (word
// c / 64, bit c % 64) is cell index c (cellIndexOf). A cell is occupied, free, or unknown
// (neither bit set: never observed, or inside the unknown band), as OccupancyModel::state()
// says. Every writer of cells keeps them current (the backends' updates, the named edits);
// stateMasksOf() is the reference they must equal.
#pragma once

#include <cstdint>

#include "fragg_map/cell.h"
#include "fragg_map/hd.h"
#include "fragg_map/key.h"
#include "fragg_map/occupancy.h"

namespace fragg {

/// 64-bit words per mask (one bit a cell of a block).
constexpr int kStateMaskWords = kCellsPerBlock / 64;

/// The occupied and free masks of one block (128 bytes); unknown = neither.
struct BlockStateMasks {
  uint64_t occupied[kStateMaskWords] = {};
  uint64_t free[kStateMaskWords] = {};

  /// The state of cell index `cell`.
  [[nodiscard]] FRAGG_HD CellState state(int cell) const {
    const uint64_t bit = uint64_t{1} << (cell & 63);
    if (occupied[cell >> 6] & bit) return CellState::kOccupied;
    if (free[cell >> 6] & bit) return CellState::kFree;
    return CellState::kUnknown;
  }
  /// Sets the state of cell index `cell`.
  FRAGG_HD void set(int cell, CellState s) {
    const uint64_t bit = uint64_t{1} << (cell & 63);
    const int w = cell >> 6;
    occupied[w] = s == CellState::kOccupied ? occupied[w] | bit : occupied[w] & ~bit;
    free[w] = s == CellState::kFree ? free[w] | bit : free[w] & ~bit;
  }
  /// Word `w` of the unknown mask (cells neither occupied nor free).
  [[nodiscard]] FRAGG_HD uint64_t unknownWord(int w) const { return ~(occupied[w] | free[w]); }

  /// Occupied cells of the block.
  [[nodiscard]] int occupiedCount() const;
  /// Free cells of the block.
  [[nodiscard]] int freeCount() const;
  /// Whether any cell of the block is unknown.
  [[nodiscard]] bool anyUnknown() const;
};
static_assert(sizeof(BlockStateMasks) == 128, "two 512-bit masks");

/// Bitwise equality.
[[nodiscard]] bool operator==(const BlockStateMasks& a, const BlockStateMasks& b);
/// Bitwise inequality.
[[nodiscard]] inline bool operator!=(const BlockStateMasks& a, const BlockStateMasks& b) {
  return !(a == b);
}

/// The reference: the masks of `block`'s cells under `model`, recomputed from every cell.
[[nodiscard]] BlockStateMasks stateMasksOf(const Block& block, const OccupancyModel& model);

}  // namespace fragg
