#include "fragg_map/internal/dynamic_classifier.h"

#include <omp.h>

#include <algorithm>

#include "fragg_map/internal/dynamic_eval.h"
#include "fragg_map/map_params.h"
#include "fragg_map/occupancy.h"
#include "fragg_map/raycast.h"

namespace fragg {

DynamicRule DynamicRule::fromParams(const DynamicParams& p, const OccupancyParams& occupancy) {
  DynamicRule r;
  r.enabled = p.enabled;
  r.surround = p.rule == VoidSpaceRule::kSurround;
  r.void_fx = logOddsFxOf(occupancy.clamp_min);
  r.seen_free_at_or_below_fx = logOddsFxOf(p.void_probability);
  r.known_radius_cells = p.known_radius_cells;
  return r;
}

namespace {

using dynamic_eval::kWords;

// Cell lookups that remember the last block (a scan's hits share few blocks).
class CellReader {
 public:
  explicit CellReader(const BlockMap& blocks) : blocks_(blocks) {}
  const Cell* find(const VoxelKey& v) {
    const BlockKey b = blockKeyOf(v);
    if (!valid_ || b != key_) {
      key_ = b;
      const BlockIndex i = blocks_.find(b);
      block_ = i == kNoBlock ? nullptr : &blocks_.block(i);
      valid_ = true;
    }
    return block_ ? &block_->cells[cellIndexOf(v)] : nullptr;
  }

 private:
  const BlockMap& blocks_;
  BlockKey key_;
  const Block* block_ = nullptr;
  bool valid_ = false;
};

// The seen-free mask of block `key`: not hit by the scan, and passed through by it or known
// (occupied or free in the block's state masks) before it: DUFOMap's unknown inflation, where
// only unknown space and the scan's own hits keep a cell from becoming void (an occupied cell
// left by a mover's earlier hits does not). `marks_of`: the scan's marks of the block (or null).
void seenFreeMask(const BlockKey& key, const ScratchBlock* marks_of, const BlockMap& blocks,
                  uint64_t* out) {
  const BlockIndex i = blocks.find(key);
  const BlockStateMasks* masks = i == kNoBlock ? nullptr : &blocks.masks(i);
  dynamic_eval::seenFreeMask(marks_of ? marks_of->free : nullptr,
                             marks_of ? marks_of->hit : nullptr, masks ? masks->occupied : nullptr,
                             masks ? masks->free : nullptr, out);
}

}  // namespace

bool isDynamicHit(const VoxelKey& end, const BlockMap& blocks, const DynamicRule& rule) {
  CellReader cells(blocks);
  return dynamic_eval::dynamicAt(end, cells, rule);
}

void passThroughResets(const BlockKey& key, const uint64_t* free_marks, const uint64_t* hit_marks,
                       const BlockMap& blocks, const DynamicRule& rule, uint64_t* resets) {
  for (int w = 0; w < kStateMaskWords; ++w) resets[w] = 0;
  const BlockIndex i = blocks.find(key);
  if (i == kNoBlock) return;
  const BlockStateMasks& masks = blocks.masks(i);
  CellReader cells(blocks);
  for (int w = 0; w < kStateMaskWords; ++w)
    for (uint64_t bits = free_marks[w] & ~hit_marks[w] & masks.occupied[w]; bits != 0;
         bits &= bits - 1) {
      const int c = w * 64 + __builtin_ctzll(bits);
      if (dynamic_eval::observedAround(voxelKeyOf(key, c), cells, rule))
        resets[w] |= uint64_t{1} << (c & 63);
    }
}

void surroundedCells(const ScanScratch& marks, const BlockMap& blocks, const DynamicRule& rule,
                     int threads, std::vector<uint64_t>& surrounded) {
  const long touched = static_cast<long>(marks.touchedCount());
  surrounded.assign(static_cast<size_t>(touched) * kWords, 0);
  // 1. The seen-free mask of every touched block (neighbours' masks are read many times).
  std::vector<uint64_t> seen(static_cast<size_t>(touched) * kWords);
#pragma omp parallel for num_threads(threads) schedule(dynamic, 64)
  for (long j = 0; j < touched; ++j)
    seenFreeMask(marks.touched(j).key, &marks.touched(j), blocks, &seen[j * kWords]);
  // 2. Each passed-through cell against its neighbourhood (r <= 2 < a block: the 27 blocks
  // around its own hold every neighbour).
  const int r = rule.known_radius_cells;
#pragma omp parallel for num_threads(threads) schedule(dynamic, 64)
  for (long j = 0; j < touched; ++j) {
    const ScratchBlock& b = marks.touched(j);
    uint64_t candidates[kWords];
    uint64_t any = 0;
    for (int w = 0; w < kWords; ++w) any |= candidates[w] = b.free[w] & ~b.hit[w];
    if (any == 0) continue;
    const uint64_t* around[27];
    uint64_t untouched[27][kWords];
    for (int dz = -1; dz <= 1; ++dz)
      for (int dy = -1; dy <= 1; ++dy)
        for (int dx = -1; dx <= 1; ++dx) {
          const int n = (dz + 1) * 9 + (dy + 1) * 3 + (dx + 1);
          const BlockKey k{b.key.x + dx, b.key.y + dy, b.key.z + dz};
          if (const ScratchBlock* s = marks.find(k)) {
            around[n] = &seen[size_t{s->index} * kWords];
          } else {
            seenFreeMask(k, nullptr, blocks, untouched[n]);
            around[n] = untouched[n];
          }
        }
    dynamic_eval::surroundedMask(around, r, candidates, &surrounded[j * kWords]);
  }
}

void classifyDynamicHits(PreparedScan& scan, const BlockMap& blocks, const DynamicRule& rule,
                         int threads, std::vector<uint32_t>& dynamic_rays) {
  dynamic_rays.clear();
  const long n = static_cast<long>(scan.rays.size());
  std::vector<std::vector<uint32_t>> found(static_cast<size_t>(threads));
#pragma omp parallel num_threads(threads)
  {
    CellReader cells(blocks);
    std::vector<uint32_t>& local = found[omp_get_thread_num()];
#pragma omp for schedule(static)
    for (long i = 0; i < n; ++i) {
      const RayEnd& ray = scan.rays[i];
      if (!isHitCode(ray.hit)) continue;
      const size_t r = static_cast<size_t>(i);
      const VoxelKey end{scan.ref.x + scan.endCell(r, 0), scan.ref.y + scan.endCell(r, 1),
                         scan.ref.z + scan.endCell(r, 2)};
      if (dynamic_eval::dynamicAt(end, cells, rule)) local.push_back(static_cast<uint32_t>(i));
    }
  }
  // Static schedule: thread t's rays come before thread t + 1's, so the list is ascending.
  for (const std::vector<uint32_t>& f : found)
    dynamic_rays.insert(dynamic_rays.end(), f.begin(), f.end());
  for (uint32_t i : dynamic_rays) scan.rays[i].hit = 0u;
}

}  // namespace fragg
