#include "fragg_map/planning/frontier_tracker.h"

#include <fmt/format.h>
#include <omp.h>

#include <algorithm>
#include <chrono>
#include <cmath>

#include "fragg_map/block_key_table.h"
#include "fragg_map/errors.h"
#include "fragg_map/internal/thread_count.h"
#include "frontier_masks.h"

namespace fragg::planning {

namespace {

double secondsSince(std::chrono::steady_clock::time_point t0) {
  return std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
}

// One block of the map as the tracker knows it.
struct BlockRecord {
  BlockKey key;
  StateMasks state;
  FrontierBits frontier;
  uint32_t count = 0;  ///< frontier cells (after the filter)
  uint32_t mark = 0;   ///< update number that queued it for examination
};

}  // namespace

struct FrontierTracker::State {
  FrontierFilter filter;
  int threads = 0;
  bool valid = false;
  uint64_t revision = 0;
  uint64_t epoch = 0;  ///< Map::viewEpoch() at the last update
  uint64_t total = 0;
  uint32_t update_number = 0;
  bool on_device = false;  ///< the last states were read by the map's backend
  std::vector<BlockRecord> records;
  BlockKeyTable index;  ///< key -> records index

  int threadCount() const { return fragg::threadCount(threads); }

  void clear() {
    valid = false;
    revision = 0;
    total = 0;
    records.clear();
    index.clear();
  }

  /// The blocks the filter's box reaches (set by update() for the map at hand).
  BlockKey box_lo, box_hi;

  /// Whether the filter's box can hold cells of block `b` (always, without a box).
  bool inRange(const BlockKey& b) const {
    if (!filter.use_box) return true;
    return b.x >= box_lo.x && b.y >= box_lo.y && b.z >= box_lo.z && b.x <= box_hi.x &&
           b.y <= box_hi.y && b.z <= box_hi.z;
  }

  /// Recomputes the frontier bits of records `which` (parallel) and the total.
  void examine(const Map& map, const BlockView& view, const std::vector<uint32_t>& which) {
    const int64_t n = static_cast<int64_t>(which.size());
    std::vector<uint32_t> old_counts(which.size());
    for (int64_t i = 0; i < n; ++i) old_counts[i] = records[which[i]].count;
#pragma omp parallel for schedule(dynamic, 256) num_threads(threadCount())
    for (int64_t i = 0; i < n; ++i) {
      BlockRecord& r = records[which[i]];
      const StateMasks* around[27];
      for (int dz = -1, j = 0; dz <= 1; ++dz)
        for (int dy = -1; dy <= 1; ++dy)
          for (int dx = -1; dx <= 1; ++dx, ++j) {
            const uint32_t k = index.find({r.key.x + dx, r.key.y + dy, r.key.z + dz});
            around[j] = k == BlockKeyTable::kNone ? nullptr : &records[k].state;
          }
      r.frontier = frontierBitsOf(around);
      if (filter.any()) applyFilter(map, view, r);
      uint32_t count = 0;
      for (int w = 0; w < kMaskWords; ++w) count += __builtin_popcountll(r.frontier.words[w]);
      r.count = count;
    }
    for (int64_t i = 0; i < n; ++i) total = total - old_counts[i] + records[which[i]].count;
  }

  void applyFilter(const Map& map, const BlockView& view, BlockRecord& r) const {
    for (int w = 0; w < kMaskWords; ++w)
      for (uint64_t bits = r.frontier.words[w]; bits; bits &= bits - 1) {
        const int b = __builtin_ctzll(bits);
        if (!filter.keeps(map, view, voxelKeyOf(r.key, w * 64 + b)))
          r.frontier.words[w] &= ~(uint64_t(1) << b);
      }
  }

  /// State masks of `keys` into `out` (resized): on the map's backend where it has a path
  /// (CUDA: over its block cache), else from the host blocks (parallel).
  void readStates(const Map& map, const BlockView& view, const std::vector<BlockKey>& keys,
                  std::vector<StateMasks>& out) {
    out.resize(keys.size());
    static_assert(sizeof(StateMasks) == 16 * sizeof(uint64_t), "16 words per block");
    on_device =
        !keys.empty() && map.cellStateBitsOnBackend(keys, reinterpret_cast<uint64_t*>(out.data()));
    if (on_device || keys.empty()) return;
    const int64_t n = static_cast<int64_t>(keys.size());
    const OccupancyModel& model = map.model();
#pragma omp parallel for schedule(static) num_threads(threadCount())
    for (int64_t i = 0; i < n; ++i) out[i] = stateMasksOf(model, view.findBlock(keys[i]));
  }

  /// Every block read again; returns the number of records examined.
  uint64_t full(const Map& map, const BlockView& view) {
    clear();
    std::vector<BlockKey> keys;
    keys.reserve(view.size());
    view.forEach([&](const BlockKey& key, const Block&) { keys.push_back(key); });
    std::vector<StateMasks> states;
    readStates(map, view, keys, states);
    const int64_t n = static_cast<int64_t>(keys.size());
    records.resize(keys.size());
#pragma omp parallel for schedule(static) num_threads(threadCount())
    for (int64_t i = 0; i < n; ++i) {
      records[i].key = keys[i];
      records[i].state = states[i];
    }
    index.reserve(keys.size());
    std::vector<uint32_t> which;
    which.reserve(keys.size());
    for (uint32_t i = 0; i < records.size(); ++i) {
      index.insert(records[i].key, i);
      if (inRange(records[i].key)) which.push_back(i);
    }
    examine(map, view, which);
    return which.size();
  }

  /// The changed blocks read again, their neighbourhoods examined where states changed.
  /// Returns {changed blocks, records examined}.
  std::pair<uint64_t, uint64_t> incremental(const Map& map, const BlockView& view,
                                            FrontierUpdateStats& stats) {
    auto t0 = std::chrono::steady_clock::now();
    const std::vector<BlockKey> changed = view.changedSince(revision, BlockChange::kAny);
    const int64_t n = static_cast<int64_t>(changed.size());
    std::vector<StateMasks> fresh;
    readStates(map, view, changed, fresh);
    stats.states_seconds = secondsSince(t0);
    t0 = std::chrono::steady_clock::now();
    // Compare in parallel (each changed key has its own record), then add the new blocks.
    std::vector<uint32_t> found(changed.size());
    std::vector<uint8_t> moved_flag(changed.size());
#pragma omp parallel for schedule(static) num_threads(threadCount())
    for (int64_t i = 0; i < n; ++i) {
      const uint32_t k = index.find(changed[i]);
      found[i] = k;
      moved_flag[i] = k == BlockKeyTable::kNone || !(records[k].state == fresh[i]);
      if (k != BlockKeyTable::kNone && moved_flag[i]) records[k].state = fresh[i];
    }
    std::vector<BlockKey> moved;  // blocks whose cell states changed
    for (int64_t i = 0; i < n; ++i) {
      if (!moved_flag[i]) continue;
      if (found[i] == BlockKeyTable::kNone) {
        index.insert(changed[i], static_cast<uint32_t>(records.size()));
        records.push_back(BlockRecord{changed[i], fresh[i], FrontierBits{}, 0, 0});
      }
      moved.push_back(changed[i]);
    }
    // A block's states decide the frontier cells of its own and its neighbours' borders, and
    // with the obstacle distance filter those of every block within that distance. Marked in
    // parallel: the first thread to stamp a record lists it.
    const int reach_cells =
        static_cast<int>(std::ceil(filter.min_obstacle_distance_m / map.resolution()));
    const int reach = 1 + (reach_cells + kBlockMask) / kBlockSize;
    if (++update_number == 0) {
      for (BlockRecord& r : records) r.mark = 0;
      update_number = 1;
    }
    std::vector<uint32_t> which;
    const int64_t n_moved = static_cast<int64_t>(moved.size());
#pragma omp parallel num_threads(threadCount())
    {
      std::vector<uint32_t> mine;
#pragma omp for schedule(dynamic, 256) nowait
      for (int64_t i = 0; i < n_moved; ++i) {
        const BlockKey& b = moved[i];
        for (int dz = -reach; dz <= reach; ++dz)
          for (int dy = -reach; dy <= reach; ++dy)
            for (int dx = -reach; dx <= reach; ++dx) {
              const BlockKey nb{b.x + dx, b.y + dy, b.z + dz};
              const uint32_t k = index.find(nb);
              if (k == BlockKeyTable::kNone) continue;
              if (__atomic_exchange_n(&records[k].mark, update_number, __ATOMIC_RELAXED) ==
                  update_number)
                continue;
              if (inRange(nb)) mine.push_back(k);
            }
      }
#pragma omp critical(frontier_which)
      which.insert(which.end(), mine.begin(), mine.end());
    }
    stats.compare_seconds = secondsSince(t0);
    t0 = std::chrono::steady_clock::now();
    examine(map, view, which);
    stats.examine_seconds = secondsSince(t0);
    return {changed.size(), which.size()};
  }
};

FrontierTracker::FrontierTracker(const FrontierFilter& filter, int threads)
    : state_(std::make_unique<State>()) {
  filter.validate();
  if (threads < 0) throw InvalidArgument(fmt::format("threads must be >= 0, got {}", threads));
  state_->filter = filter;
  state_->threads = threads;
}

FrontierTracker::~FrontierTracker() = default;
FrontierTracker::FrontierTracker(FrontierTracker&&) noexcept = default;
FrontierTracker& FrontierTracker::operator=(FrontierTracker&&) noexcept = default;

void FrontierTracker::reset() { state_->clear(); }

uint64_t FrontierTracker::size() const { return state_->total; }
uint64_t FrontierTracker::revision() const { return state_->revision; }
const FrontierFilter& FrontierTracker::filter() const { return state_->filter; }

FrontierUpdateStats FrontierTracker::update(const Map& map) {
  const auto t0 = std::chrono::steady_clock::now();
  State& s = *state_;
  FrontierUpdateStats stats;
  const BlockView view = map.blockView();
  s.on_device = false;
  if (s.filter.use_box) {
    s.box_lo = blockKeyOf(map.keyOf(s.filter.box_min_m));
    s.box_hi = blockKeyOf(map.keyOf(s.filter.box_max_m));
  }
  stats.full = !s.valid || map.viewEpoch() != s.epoch || map.revision() < s.revision;
  if (stats.full) {
    stats.blocks_examined = s.full(map, view);
    stats.blocks_changed = view.size();
  } else if (map.revision() != s.revision) {
    std::tie(stats.blocks_changed, stats.blocks_examined) = s.incremental(map, view, stats);
  }
  stats.states_on_device = s.on_device;
  s.valid = true;
  s.revision = map.revision();
  s.epoch = map.viewEpoch();
  stats.cells = s.total;
  stats.seconds = std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
  return stats;
}

void FrontierTracker::forEachBlock(
    const std::function<void(const BlockKey&, const uint64_t* bits)>& fn) const {
  std::vector<uint32_t> with_cells;
  for (uint32_t i = 0; i < state_->records.size(); ++i)
    if (state_->records[i].count) with_cells.push_back(i);
  const auto& records = state_->records;
  std::sort(with_cells.begin(), with_cells.end(),
            [&](uint32_t a, uint32_t b) { return blockOrder(records[a].key, records[b].key); });
  for (uint32_t i : with_cells) fn(records[i].key, records[i].frontier.words);
}

std::vector<VoxelKey> FrontierTracker::cells() const {
  std::vector<VoxelKey> out;
  out.reserve(state_->total);
  forEachBlock([&](const BlockKey& b, const uint64_t* bits) {
    for (int w = 0; w < kMaskWords; ++w)
      for (uint64_t m = bits[w]; m; m &= m - 1)
        out.push_back(voxelKeyOf(b, w * 64 + __builtin_ctzll(m)));
  });
  return out;
}

}  // namespace fragg::planning
