#include "fragg_map/internal/dynamic_classifier.h"

#include <omp.h>

#include <algorithm>

#include "fragg_map/map_params.h"
#include "fragg_map/raycast.h"

namespace fragg {

DynamicRule DynamicRule::fromParams(const DynamicParams& p) {
  DynamicRule r;
  r.enabled = p.enabled;
  r.void_at_or_below_fx = logOddsFxOf(p.void_probability);
  r.known_radius_cells = p.known_radius_cells;
  return r;
}

namespace {

// Cell lookups that remember the last block (a hit's neighbours share few blocks).
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

bool observedAround(const VoxelKey& end, CellReader& cells, const DynamicRule& rule) {
  const int r = rule.known_radius_cells;
  for (int dz = -r; dz <= r; ++dz)
    for (int dy = -r; dy <= r; ++dy)
      for (int dx = -r; dx <= r; ++dx) {
        const Cell* n = cells.find({end.x + dx, end.y + dy, end.z + dz});
        if (!n || !n->observed()) return false;
      }
  return true;
}

bool dynamicAt(const VoxelKey& end, CellReader& cells, const DynamicRule& rule) {
  const Cell* c = cells.find(end);
  if (!c || !rule.isVoid(*c)) return false;
  return observedAround(end, cells, rule);
}

}  // namespace

bool isDynamicHit(const VoxelKey& end, const BlockMap& blocks, const DynamicRule& rule) {
  CellReader cells(blocks);
  return dynamicAt(end, cells, rule);
}

bool neighbourhoodObserved(const VoxelKey& v, const BlockMap& blocks, const DynamicRule& rule) {
  CellReader cells(blocks);
  return observedAround(v, cells, rule);
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
      if (observedAround(voxelKeyOf(key, c), cells, rule)) resets[w] |= uint64_t{1} << (c & 63);
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
      const VoxelKey end{scan.ref.x + floorToInt(ray.end_v[0]),
                         scan.ref.y + floorToInt(ray.end_v[1]),
                         scan.ref.z + floorToInt(ray.end_v[2])};
      if (dynamicAt(end, cells, rule)) local.push_back(static_cast<uint32_t>(i));
    }
  }
  // Static schedule: thread t's rays come before thread t + 1's, so the list is ascending.
  for (const std::vector<uint32_t>& f : found)
    dynamic_rays.insert(dynamic_rays.end(), f.begin(), f.end());
  for (uint32_t i : dynamic_rays) scan.rays[i].hit = 0u;
}

}  // namespace fragg
