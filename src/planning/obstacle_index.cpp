#include "obstacle_index.h"

#include <omp.h>

#include <algorithm>

#include "fragg_map/internal/thread_count.h"

namespace fragg::planning {

ObstacleIndex::ObstacleIndex(const BlockView& view, const BlockKey& lo, const BlockKey& hi,
                             bool unknown_is_occupied, int threads)
    : default_word_(unknown_is_occupied ? ~uint64_t{0} : 0) {
  const std::vector<BlockRef> blocks = view.in(lo, hi);
  const int64_t n = static_cast<int64_t>(blocks.size());
  std::vector<uint64_t> all(blocks.size() * kMaskWords);
  std::vector<uint8_t> keep(blocks.size(), 0);
  const int use_threads = threadCount(threads);
  // The map's state masks are obstacle masks already: occupied, or not free with
  // unknown_is_occupied (no cell is read).
#pragma omp parallel for schedule(static) num_threads(use_threads)
  for (int64_t b = 0; b < n; ++b) {
    const BlockStateMasks* m = view.findMasks(blocks[b].key);
    uint64_t* words = all.data() + b * kMaskWords;
    for (int w = 0; w < kMaskWords; ++w) {
      words[w] = unknown_is_occupied ? ~m->free[w] : m->occupied[w];
      if (words[w] != default_word_) keep[b] = 1;
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
