#include "obstacle_index.h"

#include <omp.h>

#include <algorithm>
#include <cstring>

#include "fragg_map/internal/thread_count.h"

namespace fragg::planning {

namespace {
// OccupancyModel::state without branches, one byte per cell: occupied <=> log-odds above the
// occupied threshold (never true for the unobserved value, the lowest int16); free <=>
// observed, not occupied and below the free threshold; unknown otherwise. Built with the
// cost model that vectorises these loops (GCC's -O2 one does not).
__attribute__((optimize("vect-cost-model=dynamic"))) void classifyCells(const Cell* cells,
                                                                        int occupied_above,
                                                                        int free_below,
                                                                        bool unknown_is_occupied,
                                                                        uint8_t* flags) {
  if (unknown_is_occupied) {
    for (int i = 0; i < kCellsPerBlock; ++i) {
      const int lo = cells[i].log_odds_fx;
      flags[i] = !(lo != kUnobservedLogOdds && lo <= occupied_above && lo < free_below);
    }
  } else {
    for (int i = 0; i < kCellsPerBlock; ++i) flags[i] = cells[i].log_odds_fx > occupied_above;
  }
}
}  // namespace

ObstacleIndex::ObstacleIndex(const Map& map, const BlockView& view, const BlockKey& lo,
                             const BlockKey& hi, bool unknown_is_occupied, int threads)
    : default_word_(unknown_is_occupied ? ~uint64_t{0} : 0) {
  const std::vector<BlockRef> blocks = view.in(lo, hi);
  const int64_t n = static_cast<int64_t>(blocks.size());
  std::vector<uint64_t> all(blocks.size() * kMaskWords);
  std::vector<uint8_t> keep(blocks.size(), 0);
  const OccupancyModel& model = map.model();
  const int occupied_above = model.occupied_above_fx, free_below = model.free_below_fx;
  const int use_threads = threadCount(threads);
#pragma omp parallel for schedule(static) num_threads(use_threads)
  for (int64_t b = 0; b < n; ++b) {
    const Cell* cells = blocks[b].block->cells;
    uint64_t* words = all.data() + b * kMaskWords;
    // One byte per cell first, then 8 bytes -> 8 bits by a multiplication (byte i of x, 0 or
    // 1, lands on bit 56 + i of x * kPack; little-endian).
    uint8_t flags[kCellsPerBlock];
    classifyCells(cells, occupied_above, free_below, unknown_is_occupied, flags);
    constexpr uint64_t kPack = 0x0102040810204080ULL;
    for (int w = 0; w < kMaskWords; ++w) {
      uint64_t word = 0;
      for (int byte = 0; byte < 8; ++byte) {
        uint64_t eight;
        std::memcpy(&eight, flags + w * 64 + byte * 8, 8);
        word |= ((eight * kPack) >> 56) << (8 * byte);
      }
      words[w] = word;
      if (word != default_word_) keep[b] = 1;
    }
  }
  size_t kept = 0;
  for (uint8_t k : keep) kept += k;
  uint32_t capacity = 16;
  while (capacity < 2 * kept) capacity *= 2;
  keys_.assign(capacity, BlockKey{kEmptyMaskKey, 0, 0});
  slots_.assign(capacity, -1);
  masks_.reserve(kept * kMaskWords);
  for (size_t b = 0; b < blocks.size(); ++b) {
    if (!keep[b]) continue;
    const int32_t slot = static_cast<int32_t>(masks_.size() / kMaskWords);
    masks_.insert(masks_.end(), all.begin() + b * kMaskWords, all.begin() + (b + 1) * kMaskWords);
    uint32_t i = maskTableHash(blocks[b].key) & (capacity - 1);
    while (keys_[i].x != kEmptyMaskKey) i = (i + 1) & (capacity - 1);
    keys_[i] = blocks[b].key;
    slots_[i] = slot;
  }
}

ObstacleMasksView ObstacleIndex::view() const {
  ObstacleMasksView v;
  v.keys = keys_.data();
  v.slots = slots_.data();
  v.masks = masks_.data();
  v.capacity_mask = static_cast<uint32_t>(keys_.size() - 1);
  v.default_word = default_word_;
  return v;
}

}  // namespace fragg::planning
