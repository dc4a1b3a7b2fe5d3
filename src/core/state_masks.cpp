#include "fragg_map/state_masks.h"

namespace fragg {

int BlockStateMasks::occupiedCount() const {
  int n = 0;
  for (uint64_t w : occupied) n += __builtin_popcountll(w);
  return n;
}

int BlockStateMasks::freeCount() const {
  int n = 0;
  for (uint64_t w : free) n += __builtin_popcountll(w);
  return n;
}

bool BlockStateMasks::anyUnknown() const {
  for (int w = 0; w < kStateMaskWords; ++w)
    if (unknownWord(w) != 0) return true;
  return false;
}

bool operator==(const BlockStateMasks& a, const BlockStateMasks& b) {
  for (int w = 0; w < kStateMaskWords; ++w)
    if (a.occupied[w] != b.occupied[w] || a.free[w] != b.free[w]) return false;
  return true;
}

BlockStateMasks stateMasksOf(const Block& block, const OccupancyModel& model) {
  BlockStateMasks m;
  for (int c = 0; c < kCellsPerBlock; ++c) {
    const CellState s = model.state(block.cells[c]);
    const uint64_t bit = uint64_t{1} << (c & 63);
    if (s == CellState::kOccupied) m.occupied[c >> 6] |= bit;
    if (s == CellState::kFree) m.free[c >> 6] |= bit;
  }
  return m;
}

}  // namespace fragg
