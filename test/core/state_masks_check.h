// Checks of the state-mask layer shared by the core, paging and GPU tests: every block's masks
// against the reference recomputed from its cells (stateMasksOf).
#pragma once

#include <cstring>
#include <string>

#include "fragg_map/map.h"
#include "fragg_map/state_masks.h"

namespace fragg::test {

/// Blocks of `map` whose kept masks differ from the masks recomputed from their cells with the
/// map's model; `first` (optional) names the first such block. Resident blocks only.
inline size_t blocksWithStaleMasks(const Map& map, std::string* first = nullptr) {
  const BlockView view = map.blockView();
  size_t stale = 0;
  view.forEach([&](const BlockKey& key, const Block& block) {
    const BlockStateMasks* kept = view.findMasks(key);
    if (kept && *kept == stateMasksOf(block, map.model())) return;
    if (stale++ == 0 && first)
      *first = "block (" + std::to_string(key.x) + "," + std::to_string(key.y) + "," +
               std::to_string(key.z) + ")" + (kept ? "" : ": no masks");
  });
  return stale;
}

/// Blocks of `a` whose masks are not byte-identical to those of the same block of `b` (a block
/// missing from `b` counts); `first` (optional) names the first.
inline size_t blocksWithOtherMasks(const Map& a, const Map& b, std::string* first = nullptr) {
  const BlockView va = a.blockView(), vb = b.blockView();
  size_t other = 0;
  va.forEach([&](const BlockKey& key, const Block&) {
    const BlockStateMasks* ma = va.findMasks(key);
    const BlockStateMasks* mb = vb.findMasks(key);
    if (ma && mb && std::memcmp(ma, mb, sizeof(BlockStateMasks)) == 0) return;
    if (other++ == 0 && first)
      *first = "block (" + std::to_string(key.x) + "," + std::to_string(key.y) + "," +
               std::to_string(key.z) + ")";
  });
  return other;
}

}  // namespace fragg::test
