#include "fragg_map/planning/frontier_tracker.h"

#include <fmt/format.h>
#include <omp.h>

#include <algorithm>
#include <atomic>
#include <chrono>
#include <cmath>
#include <cstdint>
#include <optional>
#include <string>

#include "fragg_map/block_key_table.h"
#include "fragg_map/errors.h"
#include "fragg_map/internal/seconds_since.h"
#include "fragg_map/internal/thread_count.h"
#include "frontier_masks.h"
#if FRAGG_HAVE_CUDA
#include "cuda/device_frontiers.h"
#endif

namespace fragg::planning {

// Not in the anonymous namespace: FrontierTracker::State (external linkage) holds them.
namespace frontier_tracker_detail {

// One block of the map as the tracker knows it.
struct BlockRecord {
  BlockKey key;
  StateMasks state;
  FrontierBits frontier;
  uint32_t count = 0;  ///< frontier cells (after the filter)
  uint32_t mark = 0;   ///< update number that queued it for examination
};

}  // namespace frontier_tracker_detail

using frontier_tracker_detail::BlockRecord;

namespace {

// A cell's centre and a point's cell at `resolution_m`, as Map::centerOf and Map::keyOf.
Eigen::Vector3d centreOf(const VoxelKey& key, double resolution_m) {
  return (Eigen::Vector3d(key.x, key.y, key.z) + Eigen::Vector3d::Constant(0.5)) * resolution_m;
}

VoxelKey keyAt(const Eigen::Vector3d& p_map, double resolution_m) {
  const Eigen::Vector3d v = p_map / resolution_m;
  if (!v.allFinite() || v.cwiseAbs().maxCoeff() >= 2147483647.0)
    throw InvalidArgument("frontier filter box: a corner is outside the map's key range");
  return {static_cast<int32_t>(std::floor(v.x())), static_cast<int32_t>(std::floor(v.y())),
          static_cast<int32_t>(std::floor(v.z()))};
}

}  // namespace

struct FrontierTracker::State {
  FrontierFilter filter;
  int threads = 0;
  bool valid = false;
  uint64_t revision = 0;
  uint64_t epoch = 0;  ///< Map::viewEpoch() at the last update
  uint64_t total = 0;
  uint32_t update_number = 0;
  std::vector<BlockRecord> records;
  BlockKeyTable index;  ///< key -> records index
  /// The set lives on the map's device (updateOnDevice): `records` hold no masks then, and
  /// hold the frontier bits only once downloaded (`records_current`).
  bool on_device = false;
  bool records_current = true;
  bool device_updates = true;  ///< useDevice()
#if FRAGG_HAVE_CUDA
  std::unique_ptr<DeviceFrontiers> device;
#endif

  int threadCount() const { return fragg::threadCount(threads); }

  void clear() {
    valid = false;
    revision = 0;
    total = 0;
    records.clear();
    index.clear();
    on_device = false;
    records_current = true;
  }

  /// The frontier bits into `records` when the set lives on the device (no masks, no index:
  /// what forEachBlock reads).
  void download() {
#if FRAGG_HAVE_CUDA
    if (!on_device || records_current) return;
    std::vector<BlockKey> keys;
    std::vector<FrontierBits> bits;
    device->download(&keys, &bits);
    records.clear();
    index.clear();
    records.resize(keys.size());
    for (size_t i = 0; i < keys.size(); ++i) {
      records[i].key = keys[i];
      records[i].frontier = bits[i];
      uint32_t count = 0;
      for (int w = 0; w < kMaskWords; ++w) count += __builtin_popcountll(bits[i].words[w]);
      records[i].count = count;
    }
    records_current = true;
#endif
  }

  /// The update on the map's device (a CUDA map: the whole map's device layer view, compared
  /// slot by slot with what the tracker saw there, examined there; only counts come back).
  /// False when the map has no device view or the state does not fit there: the host update.
  bool updateOnDevice(const Map& map, FrontierUpdateStats& stats) {
#if FRAGG_HAVE_CUDA
    if (!device_updates || filter.min_obstacle_distance_m > 0.0 ||
        std::string(map.backendName()) != "cuda")
      return false;
    const auto t0 = std::chrono::steady_clock::now();
    constexpr int32_t kLo = INT32_MIN, kHi = INT32_MAX;
    const std::unique_ptr<DeviceViewLease> lease =
        map.deviceView(BlockKey{kLo, kLo, kLo}, BlockKey{kHi, kHi, kHi});
    if (!lease) return false;
    const DeviceLayerView& view = lease->view();
    stats.states_seconds = secondsSince(t0);
    const bool full = !valid || !on_device || map.revision() < revision || !device ||
                      device->device() != view.device;
    stats.full = full;
    stats.states_on_device = true;
    if (!full && map.revision() == revision) return true;  // nothing changed
    try {
      if (!device || device->device() != view.device)
        device = std::make_unique<DeviceFrontiers>(filter, view.device);
      checkQuery(control, "frontier update");
      const DeviceFrontierUpdate r = device->update(view, map.resolution(), box_lo, box_hi, full);
      if (full) {
        records.clear();
        index.clear();
        total = 0;
      }
      total = static_cast<uint64_t>(static_cast<int64_t>(total) + r.delta);
      on_device = true;
      records_current = false;
      stats.blocks_changed = r.changed;
      stats.blocks_examined = r.examined;
      stats.compare_seconds = r.compare_seconds;
      stats.examine_seconds = r.examine_seconds;
    } catch (const CudaOutOfMemory&) {
      clear();
      device.reset();
      return false;  // the host update (a full one) instead
    }
    return true;
#else
    (void)map, (void)stats;
    return false;
#endif
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
  /// The query's control (update()'s), checked every kCheckEvery records examined.
  const QueryControl* control = nullptr;
  static constexpr int64_t kCheckEvery = 4096;

  /// `map` and `view`: needed by the obstacle distance filter only (null otherwise); the box
  /// and height tests place cells with `resolution_m`.
  void examine(const Map* map, const BlockView* view, double resolution_m,
               const std::vector<uint32_t>& which) {
    const int64_t n = static_cast<int64_t>(which.size());
    std::vector<uint32_t> old_counts(which.size());
    for (int64_t i = 0; i < n; ++i) old_counts[i] = records[which[i]].count;
    std::atomic<bool> stop{false};
#pragma omp parallel for schedule(dynamic, 256) num_threads(threadCount())
    for (int64_t i = 0; i < n; ++i) {
      if (stop.load(std::memory_order_relaxed)) continue;
      if (control && i % kCheckEvery == 0 && control->stopped()) stop = true;
      BlockRecord& r = records[which[i]];
      const StateMasks* around[27];
      for (int dz = -1, j = 0; dz <= 1; ++dz)
        for (int dy = -1; dy <= 1; ++dy)
          for (int dx = -1; dx <= 1; ++dx, ++j) {
            const uint32_t k = index.find({r.key.x + dx, r.key.y + dy, r.key.z + dz});
            around[j] = k == BlockKeyTable::kNone ? nullptr : &records[k].state;
          }
      r.frontier = frontierBitsOf(around);
      if (filter.any()) applyFilter(map, view, resolution_m, r);
      uint32_t count = 0;
      for (int w = 0; w < kMaskWords; ++w) count += __builtin_popcountll(r.frontier.words[w]);
      r.count = count;
    }
    checkQuery(control, "frontier update");  // throws once stopped (the caller forgets the set)
    for (int64_t i = 0; i < n; ++i) total = total - old_counts[i] + records[which[i]].count;
  }

  /// `map`, `view`: the map and its host view, needed by the obstacle distance filter only.
  void applyFilter(const Map* map, const BlockView* view, double resolution_m,
                   BlockRecord& r) const {
    const bool cells = filter.min_obstacle_distance_m > 0.0;
    for (int w = 0; w < kMaskWords; ++w)
      for (uint64_t bits = r.frontier.words[w]; bits; bits &= bits - 1) {
        const int b = __builtin_ctzll(bits);
        const VoxelKey key = voxelKeyOf(r.key, w * 64 + b);
        const bool keep = cells ? filter.keeps(*map, *view, key)
                                : filter.keepsCentre(centreOf(key, resolution_m));
        if (!keep) r.frontier.words[w] &= ~(uint64_t(1) << b);
      }
  }

  /// Every block read again; returns the number of records examined.
  uint64_t full(const Map& map, const BlockView& view) {
    std::vector<BlockKey> keys;
    keys.reserve(view.size());
    view.forEach([&](const BlockKey& key, const Block&) { keys.push_back(key); });
    std::vector<const BlockStateMasks*> masks(keys.size());
    for (size_t i = 0; i < keys.size(); ++i) masks[i] = view.findMasks(keys[i]);
    return fullFrom(keys, masks.data(), &map, &view, map.resolution());
  }

  /// Every block of `keys` (masks[i] its masks) read again: the set from scratch.
  uint64_t fullFrom(const std::vector<BlockKey>& keys, const BlockStateMasks* const* masks,
                    const Map* map, const BlockView* view, double resolution_m) {
    clear();
    const int64_t n = static_cast<int64_t>(keys.size());
    records.resize(keys.size());
#pragma omp parallel for schedule(static) num_threads(threadCount())
    for (int64_t i = 0; i < n; ++i) {
      records[i].key = keys[i];
      records[i].state = statesOf(*masks[i]);
    }
    index.reserve(keys.size());
    std::vector<uint32_t> which;
    which.reserve(keys.size());
    for (uint32_t i = 0; i < records.size(); ++i) {
      index.insert(records[i].key, i);
      if (inRange(records[i].key)) which.push_back(i);
    }
    examine(map, view, resolution_m, which);
    return which.size();
  }

  /// The blocks whose state masks changed (the map's changed-block list: no cell is read), and
  /// the neighbourhoods their changes reach examined again. False when the list no longer
  /// reaches back to the last update (the caller recomputes in full).
  bool incremental(const Map& map, const BlockView* view, FrontierUpdateStats& stats) {
    const auto t0 = std::chrono::steady_clock::now();
    std::vector<BlockKey> changed;
    std::vector<BlockStateMasks> masks;
    if (!map.masksChangedSince(revision, &changed, &masks)) return false;
    stats.states_seconds = secondsSince(t0);
    incrementalFrom(changed, masks, &map, view, map.resolution(), stats);
    return true;
  }

  /// The incremental update from the changed-block list (`changed`, their `masks`).
  void incrementalFrom(const std::vector<BlockKey>& changed,
                       const std::vector<BlockStateMasks>& masks, const Map* map,
                       const BlockView* view, double resolution_m, FrontierUpdateStats& stats) {
    const int64_t n = static_cast<int64_t>(changed.size());
    stats.blocks_changed = changed.size();
    auto t0 = std::chrono::steady_clock::now();
    // Compare in parallel (each changed key has its own record), then add the new blocks. A
    // block's unknown cells decide its neighbours' frontier cells across the faces, edges and
    // corners they share, so only the neighbours whose side saw an unknown cell come or go are
    // examined again (`reach_bits`, one bit per neighbour); its free cells only its own.
    std::vector<uint32_t> found(changed.size());
    std::vector<uint32_t> reach_bits(changed.size());
#pragma omp parallel for schedule(static) num_threads(threadCount())
    for (int64_t i = 0; i < n; ++i) {
      const StateMasks fresh = statesOf(masks[i]);
      const uint32_t k = index.find(changed[i]);
      found[i] = k;
      const StateMasks* old = k == BlockKeyTable::kNone ? nullptr : &records[k].state;
      reach_bits[i] = old && *old == fresh ? 0 : neighboursReached(old, fresh);
      if (old && reach_bits[i]) records[k].state = fresh;
    }
    std::vector<std::pair<BlockKey, uint32_t>> moved;  // blocks whose cell states changed
    for (int64_t i = 0; i < n; ++i) {
      if (!reach_bits[i]) continue;
      if (found[i] == BlockKeyTable::kNone) {
        index.insert(changed[i], static_cast<uint32_t>(records.size()));
        records.push_back(BlockRecord{changed[i], statesOf(masks[i]), FrontierBits{}, 0, 0});
      }
      moved.emplace_back(changed[i], reach_bits[i]);
    }
    // With the obstacle distance filter a block's occupied cells decide the frontier cells of
    // every block within that distance. Marked in parallel: the first thread to stamp a record
    // lists it.
    const int reach_cells =
        static_cast<int>(std::ceil(filter.min_obstacle_distance_m / resolution_m));
    const int reach = reach_cells > 0 ? 1 + (reach_cells + kBlockMask) / kBlockSize : 1;
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
        const BlockKey& b = moved[i].first;
        const uint32_t bits = reach > 1 ? ~0u : moved[i].second;
        for (int dz = -reach; dz <= reach; ++dz)
          for (int dy = -reach; dy <= reach; ++dy)
            for (int dx = -reach; dx <= reach; ++dx) {
              if (reach == 1 && !(bits >> ((dz + 1) * 9 + (dy + 1) * 3 + (dx + 1)) & 1)) continue;
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
    examine(map, view, resolution_m, which);
    stats.examine_seconds = secondsSince(t0);
    stats.blocks_examined = which.size();
  }

  /// The filter box's block range at `resolution_m` (as Map::keyOf places its corners).
  void setBox(double resolution_m) {
    if (!filter.use_box) return;
    box_lo = blockKeyOf(keyAt(filter.box_min_m, resolution_m));
    box_hi = blockKeyOf(keyAt(filter.box_max_m, resolution_m));
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

void FrontierTracker::useDevice(bool on) {
  if (on == state_->device_updates) return;
  state_->device_updates = on;
  state_->clear();  // the next update is a full one on the path chosen
}

uint64_t FrontierTracker::size() const { return state_->total; }
uint64_t FrontierTracker::revision() const { return state_->revision; }
const FrontierFilter& FrontierTracker::filter() const { return state_->filter; }

FrontierUpdateStats FrontierTracker::update(const Map& map, const QueryControl* control) {
  try {
    state_->control = control;
    FrontierUpdateStats stats = updateChecked(map);
    state_->control = nullptr;
    return stats;
  } catch (...) {
    state_->control = nullptr;
    state_->clear();  // a stopped or failed update leaves no half-updated set behind
    throw;
  }
}

FrontierUpdateStats FrontierTracker::updateChecked(const Map& map) {
  checkQuery(state_->control, "frontier update");
  const auto t0 = std::chrono::steady_clock::now();
  State& s = *state_;
  FrontierUpdateStats stats;
  s.setBox(map.resolution());
  if (s.updateOnDevice(map, stats)) {
    s.valid = true;
    s.revision = map.revision();
    s.epoch = map.viewEpoch();
    stats.cells = s.total;
    stats.seconds = secondsSince(t0);
    return stats;
  }
  if (s.on_device) s.clear();  // the host set was not kept: a full host update
  // The host view syncs a device backend's blocks into the host map: taken only for a full
  // recompute and for the obstacle distance filter, which reads cells.
  std::optional<BlockView> view;
  if (s.filter.min_obstacle_distance_m > 0.0) view.emplace(map.blockView());
  stats.full = !s.valid || map.viewEpoch() != s.epoch || map.revision() < s.revision;
  if (!stats.full && map.revision() != s.revision) {
    stats.full = !s.incremental(map, view ? &*view : nullptr, stats);
    stats.states_on_device = !stats.full && std::string(map.backendName()) == "cuda";
  }
  if (stats.full) {
    if (!view) view.emplace(map.blockView());
    stats.blocks_examined = s.full(map, *view);
    stats.blocks_changed = view->size();
  }
  s.valid = true;
  s.revision = map.revision();
  s.epoch = map.viewEpoch();
  stats.cells = s.total;
  stats.seconds = std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
  return stats;
}

FrontierMapChanges FrontierTracker::collect(const Map& map) const {
  if (state_->filter.min_obstacle_distance_m > 0.0)
    throw InvalidArgument(
        "frontier tracker: a filter with min_obstacle_distance_m reads cells: update() under "
        "the map's lock instead of collect() and apply()");
  const State& s = *state_;
  FrontierMapChanges c;
  c.base_revision = s.revision;
  c.base_valid = s.valid;
  c.revision = map.revision();
  c.view_epoch = map.viewEpoch();
  c.resolution_m = map.resolution();
  c.full = !s.valid || s.on_device || map.viewEpoch() != s.epoch || map.revision() < s.revision;
  if (!c.full && map.revision() == s.revision) return c;  // nothing changed
  if (!c.full && map.masksChangedSince(s.revision, &c.keys, &c.masks)) return c;
  c.full = true;
  c.keys.clear();
  c.masks.clear();
  const BlockView view = map.blockView();
  c.keys.reserve(view.size());
  view.forEach([&](const BlockKey& key, const Block&) { c.keys.push_back(key); });
  c.masks.resize(c.keys.size());
  for (size_t i = 0; i < c.keys.size(); ++i) c.masks[i] = *view.findMasks(c.keys[i]);
  return c;
}

FrontierUpdateStats FrontierTracker::apply(const FrontierMapChanges& changes,
                                           const QueryControl* control) {
  State& s = *state_;
  if (!changes.full && (changes.base_revision != s.revision || changes.base_valid != s.valid))
    throw InvalidArgument(
        "frontier tracker: changes collected at another revision than the tracker's (collect "
        "and apply in pairs)");
  if (changes.keys.size() != changes.masks.size())
    throw InvalidArgument("frontier tracker: changes with " + std::to_string(changes.keys.size()) +
                          " keys and " + std::to_string(changes.masks.size()) + " masks");
  try {
    s.control = control;
    checkQuery(control, "frontier update");
    const auto t0 = std::chrono::steady_clock::now();
    FrontierUpdateStats stats;
    s.setBox(changes.resolution_m);
    stats.full = changes.full;
    if (changes.full) {
      std::vector<const BlockStateMasks*> masks(changes.masks.size());
      for (size_t i = 0; i < masks.size(); ++i) masks[i] = &changes.masks[i];
      stats.blocks_examined =
          s.fullFrom(changes.keys, masks.data(), nullptr, nullptr, changes.resolution_m);
      stats.blocks_changed = changes.keys.size();
    } else if (changes.revision != s.revision) {
      s.incrementalFrom(changes.keys, changes.masks, nullptr, nullptr, changes.resolution_m, stats);
    }
    s.valid = true;
    s.revision = changes.revision;
    s.epoch = changes.view_epoch;
    stats.cells = s.total;
    stats.seconds = secondsSince(t0);
    s.control = nullptr;
    return stats;
  } catch (...) {
    s.control = nullptr;
    s.clear();  // a stopped or failed update leaves no half-updated set behind
    throw;
  }
}

void FrontierTracker::forEachBlock(
    const std::function<void(const BlockKey&, const uint64_t* bits)>& fn) const {
  state_->download();
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
