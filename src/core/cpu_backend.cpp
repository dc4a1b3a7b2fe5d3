#include "fragg_map/internal/cpu_backend.h"

#include <omp.h>

#include <algorithm>
#include <chrono>
#include <cmath>
#include <iterator>
#include <vector>

#include "fragg_map/internal/decay.h"
#include "fragg_map/internal/dynamic_classifier.h"
#include "fragg_map/internal/seconds_since.h"
#include "fragg_map/internal/thread_count.h"
#include "fragg_map/raycast.h"
#include "fragg_map/raycast_octomap.h"

namespace fragg {

namespace {
/// Marks the cells of rays in the scratch. Follows the ray from block to block through the
/// blocks' face-neighbour links; other lookups go through a small direct-mapped cache of
/// recent blocks (neighbouring rays share blocks) before the scratch's table. When inserting,
/// free cells of blocks whose every cell is at the lower clamp are not marked (a miss changes
/// nothing there) and the traversal walks past the rest of such a block.
struct MarkCells {
  static constexpr int kCacheSize = 256;
  struct CacheEntry {
    BlockKey key;
    ScratchBlock* block = nullptr;
  };
  ScanScratch* scratch = nullptr;
  const BlockMap* map = nullptr;  ///< null: no block is skipped (removal)
  /// Paging: a block the map lacks may be paged out saturated (null: none is).
  const PagedOutSaturated* paged_out_saturated = nullptr;
  ScratchBlock* current = nullptr;
  bool skip_block = false;  ///< the last free cell's block is skipped
  CacheEntry cache[kCacheSize];

  bool skippingBlock() const { return skip_block; }

  ScratchBlock* lookup(const BlockKey& b) {
    const uint32_t h = (static_cast<uint32_t>(b.x) * 73856093u) ^
                       (static_cast<uint32_t>(b.y) * 19349669u) ^
                       (static_cast<uint32_t>(b.z) * 83492791u);
    CacheEntry& e = cache[(h ^ (h >> 16)) & (kCacheSize - 1)];
    if (!e.block || e.key != b) {
      e.block = &scratch->blockFor(b);
      e.key = b;
      if (e.block->skip_free < 0) {
        const BlockIndex i = map ? map->find(b) : kNoBlock;
        if (i != kNoBlock)
          e.block->skip_free = map->meta(i).freeSaturated() ? 1 : 0;
        else
          e.block->skip_free = map && paged_out_saturated && (*paged_out_saturated)(b) ? 1 : 0;
      }
    }
    return e.block;
  }

  void operator()(const VoxelKey& v, bool hit, int entry) {
    if (entry >= 0) {
      ScratchBlock*& next = current->neighbour[entry];
      if (!next) next = lookup(blockKeyOf(v));
      current = next;
    } else if (entry == kUnknownBlock) {
      current = lookup(blockKeyOf(v));
    }
    skip_block = !hit && current->skip_free > 0;
    if (!skip_block) current->mark(cellIndexOf(v), hit);
  }
};

/// Whether a miss would change no cell of the block. `masks`: the block's state masks; when the
/// lower clamp reads free (any sensible model), a block with a cell that is not free has a cell
/// above the clamp, which the masks tell without reading the cells.
bool allAtLowerClamp(const Block& block, const BlockStateMasks& masks,
                     const OccupancyModel& model) {
  if (model.min_fx < model.free_below_fx) {
    uint64_t all_free = ~uint64_t{0};
    for (uint64_t w : masks.free) all_free &= w;
    if (all_free != ~uint64_t{0}) return false;
  }
  bool all = true;
  for (const Cell& c : block.cells) all &= c.log_odds_fx == model.min_fx;
  return all;
}

/// Bounding box, in blocks, of every cell the scan's rays can touch.
void scanBlockBounds(const PreparedScan& scan, BlockKey* lo, BlockKey* hi) {
  int mn[3], mx[3];  // cells relative to ref
  for (int a = 0; a < 3; ++a) mn[a] = mx[a] = floorToInt(scan.start_v[a]);
  for (size_t i = 0; i < scan.rays.size(); ++i)
    for (int a = 0; a < 3; ++a) {
      const int c = scan.endCell(i, a);
      mn[a] = std::min(mn[a], c);
      mx[a] = std::max(mx[a], c);
    }
  const int32_t ref[3] = {scan.ref.x, scan.ref.y, scan.ref.z};
  int32_t l[3], h[3];
  for (int a = 0; a < 3; ++a) {
    l[a] = (ref[a] + mn[a] - 1) >> kBlockBits;
    h[a] = (ref[a] + mx[a] + 1) >> kBlockBits;
  }
  *lo = {l[0], l[1], l[2]};
  *hi = {h[0], h[1], h[2]};
}
}  // namespace

namespace {
/// The blocks of a prepared scan's hit cells (a run of hits in one block listed once; the
/// page-in takes each key once).
std::vector<BlockKey> hitBlockKeys(const PreparedScan& scan) {
  std::vector<BlockKey> keys;
  for (size_t r = 0; r < scan.rays.size(); ++r) {
    if (!isHitCode(scan.rays[r].hit)) continue;
    const BlockKey k =
        blockKeyOf(VoxelKey{scan.ref.x + scan.endCell(r, 0), scan.ref.y + scan.endCell(r, 1),
                            scan.ref.z + scan.endCell(r, 2)});
    if (keys.empty() || !(keys.back() == k)) keys.push_back(k);
  }
  return keys;
}
}  // namespace

void CpuBackend::update(const ScanInput& in, ScanUpdate what, const UpdateSettings& how,
                        BlockMap& blocks, InsertStats& stats) {
  const auto t0 = std::chrono::steady_clock::now();
  prepareScan(in.cloud, in.T_map_sensor, in.model, in.frustum, in.explicit_model, how.params,
              prepared_, stats);
  dynamic_points_S_.clear();
  if (how.params.dynamic.enabled && what == ScanUpdate::kIntegrate) {
    // Paging: the hits' blocks and those around them back first (the rule reads a hit's
    // neighbourhood; paging in changes no cell).
    if (how.page_in_around) (*how.page_in_around)(hitBlockKeys(prepared_));
    // Hits in void space become free-only rays before any cell changes (the map as it was).
    classifyDynamicHits(prepared_, blocks,
                        DynamicRule::fromParams(how.params.dynamic, how.params.occupancy),
                        threadCount(threads_), dynamic_rays_);
    dynamic_points_S_.reserve(dynamic_rays_.size());
    for (uint32_t r : dynamic_rays_)
      dynamic_points_S_.push_back(in.cloud.points_S[prepared_.point_index[r]]);
    stats.rays_dynamic += dynamic_rays_.size();
    stats.rays_hit -= dynamic_rays_.size();
  }
  stats.seconds_prepare += secondsSince(t0);
  updatePrepared(prepared_, what, how.model, how.params.raycast, how.params.skip_saturated_blocks,
                 how, blocks, stats);
  if (how.params.dynamic.decay_log_odds_per_scan > 0.0 && what == ScanUpdate::kIntegrate) {
    // Forgetting: the whole map one step toward unknown, after the scan (its cells too).
    const auto t_decay = std::chrono::steady_clock::now();
    decayCells(blocks, how.model, decayStepFx(how.params.dynamic.decay_log_odds_per_scan),
               how.revision, threadCount(threads_));
    stats.seconds_apply += secondsSince(t_decay);
  }
}

void CpuBackend::updatePrepared(const PreparedScan& scan, ScanUpdate what,
                                const OccupancyModel& model, RayCast raycast, bool skip_saturated,
                                const UpdateSettings& how, BlockMap& blocks, InsertStats& stats) {
  const bool remove = what == ScanUpdate::kRemove;
  const uint64_t revision = how.revision;
  const PageInKeys* page_in = remove ? nullptr : how.page_in;
  const int threads = threadCount(threads_);
  auto t0 = std::chrono::steady_clock::now();
  BlockKey lo, hi;
  scanBlockBounds(scan, &lo, &hi);
  while (scratch_.size() < static_cast<size_t>(threads))
    scratch_.push_back(std::make_unique<ScanScratch>());
  struct ScratchGuard {  // the scratch must be clean for the next scan, even after a throw
    std::vector<std::unique_ptr<ScanScratch>>& all;
    ~ScratchGuard() {
      for (auto& s : all) s->end();
    }
  } guard{scratch_};
  for (int t = 0; t < threads; ++t) scratch_[t]->begin(lo, hi);

  // 1. Ray casting: each thread marks cells in its own scratch.
  uint64_t visits = 0;
  const long n = static_cast<long>(scan.rays.size());
#pragma omp parallel num_threads(threads) reduction(+ : visits)
  {
    MarkCells mark;
    mark.scratch = scratch_[omp_get_thread_num()].get();
    // An undone miss does change a clamped cell: a removal visits every cell.
    mark.map = remove || !skip_saturated ? nullptr : &blocks;
    mark.paged_out_saturated = page_in ? how.paged_out_saturated : nullptr;
#pragma omp for schedule(dynamic, 512)
    for (long i = 0; i < n; ++i) {
      const size_t r = static_cast<size_t>(i);
      if (raycast == RayCast::kOctomap) {
        const RayMetres ray = scan.rayMetres(r);
        visits += traverseOctomapKeys(ray, mark);
        continue;
      }
      const RayVox ray = scan.ray(r);
      visits +=
          raycast == RayCast::kBresenham ? traverseBresenham(ray, mark) : traverseDda(ray, mark);
    }
  }
  // 2. Merge the threads' marks into the first scratch.
  ScanScratch& merged = *scratch_[0];
  for (int t = 1; t < threads; ++t) {
    ScanScratch& other = *scratch_[t];
    for (size_t j = 0; j < other.touchedCount(); ++j) {
      const ScratchBlock& b = other.touched(j);
      merged.blockFor(b.key).orWith(b);
    }
  }
  stats.voxel_visits += visits;
  stats.seconds_raycast += secondsSince(t0);

  // 3. Apply: find or create the host blocks, then update the marked cells.
  t0 = std::chrono::steady_clock::now();
  const long touched = static_cast<long>(merged.touchedCount());
  const DynamicRule rule = DynamicRule::fromParams(how.params.dynamic, how.params.occupancy);
  const bool dynamic = how.params.dynamic.enabled && !remove;
  std::vector<BlockIndex> target(static_cast<size_t>(touched), kNoBlock);
  // A scratch block without marks was only entered by misses in a skipped block: nothing to do.
  std::vector<char> marked(static_cast<size_t>(touched), 0);
#pragma omp parallel for num_threads(threads) schedule(static)
  for (long j = 0; j < touched; ++j) {
    marked[j] = merged.touched(j).marked();
    target[j] = marked[j] ? blocks.find(merged.touched(j).key) : kNoBlock;
  }
  if (page_in) {
    // Paging: the marked blocks the map lacks may be in the store; those come back first
    // (exactly the blocks the rays reach, not the scan's whole box), with MapParams::dynamic
    // also the blocks around them that its rules read below. The pager gets every marked
    // block: it may page out others to make room for them (the budget is a hard limit), so
    // every target is found again.
    std::vector<BlockKey> keys;
    bool missing = false;
    for (long j = 0; j < touched; ++j) {
      if (!marked[j]) continue;
      keys.push_back(merged.touched(j).key);
      missing |= target[j] == kNoBlock;
    }
    const PageInKeys* call = dynamic && how.page_in_around ? how.page_in_around
                             : missing                     ? page_in
                                                           : nullptr;
    if (call) {
      (*call)(keys);
#pragma omp parallel for num_threads(threads) schedule(static)
      for (long j = 0; j < touched; ++j)
        if (marked[j]) target[j] = blocks.find(merged.touched(j).key);
    }
  }
  // MapParams::dynamic: the passed-through cells that become void (read before any cell
  // changes): occupied ones with an observed neighbourhood (pass-through rule) or those the
  // surround test passes.
  const bool pass_through = dynamic && !rule.surround;
  const bool surround = dynamic && rule.surround;
  std::vector<uint64_t> resets(pass_through ? static_cast<size_t>(touched) * kStateMaskWords : 0);
  if (pass_through) {
#pragma omp parallel for num_threads(threads) schedule(dynamic, 64)
    for (long j = 0; j < touched; ++j) {
      const ScratchBlock& b = merged.touched(j);
      passThroughResets(b.key, b.free, b.hit, blocks, rule, &resets[j * kStateMaskWords]);
    }
  }
  if (surround) surroundedCells(merged, blocks, rule, threads, surrounded_);
  uint64_t created = 0, touched_marked = 0;
  std::vector<char> fresh(static_cast<size_t>(touched), 0);
  std::vector<char> masks_changed(static_cast<size_t>(touched), 0);
  for (long j = 0; j < touched; ++j) touched_marked += marked[j] ? 1 : 0;
  // A removal has nothing to undo in a block that does not exist: none is created.
  for (long j = 0; j < touched && !remove; ++j)
    created += marked[j] && target[j] == kNoBlock ? 1 : 0;
  blocks.reserve(created);
  for (long j = 0; j < touched && !remove; ++j) {
    if (!marked[j] || target[j] != kNoBlock) continue;
    target[j] = blocks.findOrCreate(merged.touched(j).key, nullptr, /*initialise=*/false);
    fresh[j] = 1;
  }
  uint64_t updated = 0;
#pragma omp parallel for num_threads(threads) schedule(dynamic, 64) reduction(+ : updated)
  for (long j = 0; j < touched; ++j) {
    if (target[j] == kNoBlock) continue;  // removal only
    const ScratchBlock& marks = merged.touched(j);
    Block& block = blocks.block(target[j]);
    if (fresh[j]) std::fill(std::begin(block.cells), std::end(block.cells), Cell());
    // The block's state masks follow its cells (a fresh block's are all unknown already).
    BlockStateMasks& masks = blocks.masks(target[j]);
    bool changed = false, occupancy_changed = false, state_changed = false;
    uint64_t masks_differ = 0;
    for (int w = 0; w < kCellsPerBlock / 64; ++w) {
      const uint64_t marked_bits = marks.free[w] | marks.hit[w];
      uint64_t occupied_bits = 0, free_bits = 0;
      for (uint64_t bits = marked_bits; bits != 0; bits &= bits - 1) {
        const int bit = __builtin_ctzll(bits);
        Cell& cell = block.cells[w * 64 + bit];
        const Cell before = cell;
        const bool hit = (marks.hit[w] >> bit) & 1;
        if (pass_through && (resets[j * kStateMaskWords + w] >> bit) & 1) {
          cell.log_odds_fx = rule.seen_free_at_or_below_fx;
        } else {
          model.update(cell, hit, remove);
          if (surround && !hit)
            cell.log_odds_fx = rule.afterMiss(before, cell.log_odds_fx,
                                              (surrounded_[j * kStateMaskWords + w] >> bit) & 1);
        }
        changed |= before.log_odds_fx != cell.log_odds_fx || before.hits != cell.hits;
        const CellState was = model.state(before), is = model.state(cell);
        occupancy_changed |= (was == CellState::kOccupied) != (is == CellState::kOccupied);
        state_changed |= model.stateDiffers(before, cell);
        occupied_bits |= uint64_t{is == CellState::kOccupied} << bit;
        free_bits |= uint64_t{is == CellState::kFree} << bit;
        ++updated;
      }
      const uint64_t occupied_word = (masks.occupied[w] & ~marked_bits) | occupied_bits;
      const uint64_t free_word = (masks.free[w] & ~marked_bits) | free_bits;
      masks_differ |= (occupied_word ^ masks.occupied[w]) | (free_word ^ masks.free[w]);
      masks.occupied[w] = occupied_word;
      masks.free[w] = free_word;
    }
    masks_changed[j] = masks_differ != 0;
    BlockMeta& meta = blocks.meta(target[j]);
    if (changed) meta.changed_at = revision;
    if (occupancy_changed) meta.occupied_at = revision;
    if (state_changed) meta.state_at = revision;
    meta.free_saturated_at =
        allAtLowerClamp(block, masks, model) ? meta.changed_at : BlockMeta::kNotSaturated;
  }
  // The change log (serial: it appends), for readers of BlockChange::kMasks.
  for (long j = 0; j < touched; ++j)
    if (masks_changed[j]) blocks.noteMasksChanged(target[j], revision);
  stats.cells_updated += updated;
  stats.blocks_touched += touched_marked;
  stats.blocks_created += created;
  stats.seconds_apply += secondsSince(t0);
}

}  // namespace fragg
