#include "host_only_index.h"

#include <algorithm>

namespace fragg::cuda {

void HostOnlyIndex::remove(BlockIndex i, const BlockKey& key) {
  auto it = cells_.find(coarse(key));
  if (it == cells_.end()) return;
  std::vector<BlockIndex>& list = it->second;
  auto pos = std::find(list.begin(), list.end(), i);
  if (pos == list.end()) return;
  *pos = list.back();
  list.pop_back();
  if (list.empty()) cells_.erase(it);
}

void HostOnlyIndex::rebuild(const BlockMap& blocks) {
  cells_.clear();
  blocks.forEach([&](BlockIndex i) { add(i, blocks.meta(i).key); });
}

void HostOnlyIndex::forEachInBox(const BlockMap& blocks, const BlockKey& lo, const BlockKey& hi,
                                 const std::function<void(BlockIndex)>& fn) const {
  if (cells_.empty()) return;
  const BlockKey clo = coarse(lo), chi = coarse(hi);
  auto inside = [&](const BlockKey& k) {
    return k.x >= lo.x && k.x <= hi.x && k.y >= lo.y && k.y <= hi.y && k.z >= lo.z && k.z <= hi.z;
  };
  auto visit = [&](const std::vector<BlockIndex>& list) {
    for (BlockIndex i : list)
      if (inside(blocks.meta(i).key)) fn(i);
  };
  const double box =
      (double(chi.x) - clo.x + 1) * (double(chi.y) - clo.y + 1) * (double(chi.z) - clo.z + 1);
  if (box > static_cast<double>(cells_.size())) {
    for (const auto& [c, list] : cells_)
      if (c.x >= clo.x && c.x <= chi.x && c.y >= clo.y && c.y <= chi.y && c.z >= clo.z &&
          c.z <= chi.z)
        visit(list);
    return;
  }
  for (int32_t z = clo.z; z <= chi.z; ++z)
    for (int32_t y = clo.y; y <= chi.y; ++y)
      for (int32_t x = clo.x; x <= chi.x; ++x) {
        auto it = cells_.find(BlockKey{x, y, z});
        if (it != cells_.end()) visit(it->second);
      }
}

}  // namespace fragg::cuda
