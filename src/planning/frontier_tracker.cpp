#include "fragg_map/planning/frontier_tracker.h"

#include <fmt/format.h>
#include <omp.h>

#include <algorithm>
#include <chrono>
#include <cmath>
#include <unordered_set>

#include "fragg_map/errors.h"

namespace fragg::planning {

FrontierTracker::FrontierTracker(const FrontierFilter& filter, int threads)
    : filter_(filter), threads_(threads) {
  filter_.validate();
  if (threads < 0) throw InvalidArgument(fmt::format("threads must be >= 0, got {}", threads));
}

void FrontierTracker::reset() {
  valid_ = false;
  revision_ = 0;
  total_ = 0;
  by_block_.clear();
}

void FrontierTracker::recompute(const Map& map, const BlockView& view,
                                const std::vector<BlockKey>& blocks) {
  std::vector<std::vector<uint16_t>> found(blocks.size());
  const int n_threads = threads_ > 0 ? threads_ : omp_get_max_threads();
  const int64_t n = static_cast<int64_t>(blocks.size());
#pragma omp parallel for schedule(dynamic, 32) num_threads(n_threads)
  for (int64_t i = 0; i < n; ++i) found[i] = frontierCellsOfBlock(map, view, blocks[i], filter_);
  for (size_t i = 0; i < blocks.size(); ++i) {
    auto it = by_block_.find(blocks[i]);
    if (it != by_block_.end()) {
      total_ -= it->second.size();
      if (found[i].empty()) {
        by_block_.erase(it);
        continue;
      }
      it->second = std::move(found[i]);
      total_ += it->second.size();
    } else if (!found[i].empty()) {
      total_ += found[i].size();
      by_block_.emplace(blocks[i], std::move(found[i]));
    }
  }
}

FrontierUpdateStats FrontierTracker::update(const Map& map) {
  const auto t0 = std::chrono::steady_clock::now();
  FrontierUpdateStats stats;
  const BlockView view = map.blockView();
  const bool full = !valid_ || map.viewEpoch() != epoch_ || map.revision() < revision_;
  std::vector<BlockKey> blocks;
  if (full) {
    by_block_.clear();
    total_ = 0;
    if (filter_.use_box) {
      for (const BlockRef& r : view.in(blockKeyOf(map.keyOf(filter_.box_min_m)),
                                       blockKeyOf(map.keyOf(filter_.box_max_m))))
        blocks.push_back(r.key);
    } else {
      for (const BlockRef& r : view.all()) blocks.push_back(r.key);
    }
  } else if (map.revision() != revision_) {
    // A changed block changes the frontier cells of its own and of its neighbours' border,
    // and with the obstacle distance filter those of every block within that distance.
    const int reach_cells =
        static_cast<int>(std::ceil(filter_.min_obstacle_distance_m / map.resolution()));
    const int reach = 1 + (reach_cells + kBlockMask) / kBlockSize;
    std::unordered_set<BlockKey, BlockKeyHash> dirty;
    for (const BlockKey& b : view.changedSince(revision_, BlockChange::kAny))
      for (int dz = -reach; dz <= reach; ++dz)
        for (int dy = -reach; dy <= reach; ++dy)
          for (int dx = -reach; dx <= reach; ++dx) dirty.insert({b.x + dx, b.y + dy, b.z + dz});
    blocks.assign(dirty.begin(), dirty.end());
  }
  recompute(map, view, blocks);
  valid_ = true;
  revision_ = map.revision();
  epoch_ = map.viewEpoch();
  stats.full = full;
  stats.blocks_examined = blocks.size();
  stats.cells = total_;
  stats.seconds = std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
  return stats;
}

std::vector<VoxelKey> FrontierTracker::cells() const {
  std::vector<BlockKey> blocks;
  blocks.reserve(by_block_.size());
  for (const auto& entry : by_block_) blocks.push_back(entry.first);
  std::sort(blocks.begin(), blocks.end(), blockOrder);
  std::vector<VoxelKey> out;
  out.reserve(total_);
  for (const BlockKey& b : blocks)
    for (uint16_t c : by_block_.at(b)) out.push_back(voxelKeyOf(b, c));
  return out;
}

}  // namespace fragg::planning
