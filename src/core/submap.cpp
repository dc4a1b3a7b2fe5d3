// Sub-maps: Map::extract, extractOutside, truncate, truncateOutside and merge (fragg_map/submap.h).
// Every edit of this map's host blocks invalidates the backend's cache over them first, bumps the
// revision and stamps the blocks it changes.
#include <algorithm>
#include <chrono>
#include <cmath>
#include <string>
#include <unordered_set>
#include <vector>

#include "fragg_map/errors.h"
#include "fragg_map/internal/backend.h"
#include "fragg_map/internal/rigid_pose.h"
#include "fragg_map/internal/seconds_since.h"
#include "fragg_map/map.h"

namespace fragg {

namespace {
using Clock = std::chrono::steady_clock;

/// Voxel key of a point, each axis clamped into the int32 key range (a box may reach beyond
/// the map; the cells it can hold cannot).
VoxelKey clampedKeyOf(const Eigen::Vector3d& p_map, double resolution_m) {
  constexpr double kLimit = 2147483647.0 - 4.0 * kBlockSize;
  const Eigen::Vector3d v = (p_map / resolution_m).array().floor().max(-kLimit).min(kLimit);
  return {static_cast<int32_t>(v.x()), static_cast<int32_t>(v.y()), static_cast<int32_t>(v.z())};
}

/// The blocks of `blocks` that may hold cells of `region`: those the box's corners' keys span
/// (a cell centre inside the box lies in a cell between them), every block for a sphere's
/// outside.
std::vector<BlockIndex> blocksOfRegion(const BlockMap& blocks, const SubmapRegion& region,
                                       double resolution_m) {
  std::vector<BlockIndex> out;
  auto add = [&](BlockIndex i) { out.push_back(i); };
  if (region.kind == SubmapRegion::Kind::kBox)
    blocks.forEachInBox(blockKeyOf(clampedKeyOf(region.min_map, resolution_m)),
                        blockKeyOf(clampedKeyOf(region.max_map, resolution_m)), add);
  else if (region.kind == SubmapRegion::Kind::kOutsideSphere)
    blocks.forEach(add);
  return out;
}

void requireSameModel(const MapParams& map, const MapParams& sub) {
  if (map.resolution_m != sub.resolution_m)
    throw InvalidArgument("sub-map resolution " + std::to_string(sub.resolution_m) +
                          " m differs from the map's " + std::to_string(map.resolution_m) + " m");
  const OccupancyParams &a = map.occupancy, &b = sub.occupancy;
  if (a.prob_hit != b.prob_hit || a.prob_miss != b.prob_miss || a.clamp_min != b.clamp_min ||
      a.clamp_max != b.clamp_max)
    throw InvalidArgument(
        "sub-map occupancy model (prob_hit, prob_miss, clamp_min, clamp_max) differs from the "
        "map's");
}

/// A sub-map cell combined into a map cell.
Cell combined(const Cell& map_cell, const Cell& sub_cell, MergeMode mode,
              const OccupancyModel& model) {
  if (!sub_cell.observed()) return map_cell;
  if (mode == MergeMode::kOverwrite || !map_cell.observed()) return sub_cell;
  Cell c;
  c.log_odds_fx = model.clampFx(int{map_cell.log_odds_fx} + int{sub_cell.log_odds_fx});
  c.hits = static_cast<int16_t>(std::min<int>(INT16_MAX, int{map_cell.hits} + sub_cell.hits));
  return c;
}

/// Inclusive voxel-key box where a merge writes, in int64 so that overflow is detected.
struct TargetBox {
  int64_t lo[3], hi[3];
};
}  // namespace

Map Map::copyRegion(const SubmapRegion& region, Backend backend, SubmapStats* stats) const {
  const auto t0 = Clock::now();
  region.validate();
  MapParams sub_params = params_;
  sub_params.backend = backend;
  sub_params.scans = ScanStoreParams();
  sub_params.scans.keep = false;
  Map sub(sub_params);
  sub.region_ = region;
  sub.revision_ = 1;
  const BlockMap& host = hostBlocks();
  SubmapStats st;
  for (BlockIndex i : blocksOfRegion(host, region, params_.resolution_m)) {
    const BlockKey key = host.meta(i).key;
    const Block& from = host.block(i);
    BlockIndex to = kNoBlock;
    for (int c = 0; c < kCellsPerBlock; ++c) {
      if (!from.cells[c].observed() || !region.contains(centerOf(voxelKeyOf(key, c)))) continue;
      if (to == kNoBlock) {
        to = sub.blocks_.findOrCreate(key);
        BlockMeta& meta = sub.blocks_.meta(to);
        meta.changed_at = meta.occupied_at = meta.state_at = sub.revision_;
        ++st.blocks;
      }
      sub.blocks_.block(to).cells[c] = from.cells[c];
      const CellState state = sub.model_.state(from.cells[c]);
      sub.blocks_.masks(to).set(c, state);
      if (state != CellState::kUnknown) sub.blocks_.noteMasksChanged(to, sub.revision_);
      ++st.cells;
    }
  }
  st.seconds_total = secondsSince(t0);
  if (stats) *stats = st;
  return sub;
}

Map Map::moveOut(const SubmapRegion& region, Backend backend, SubmapStats* stats) {
  const auto t0 = Clock::now();
  region.validate();
  // Paged-out blocks of the region come back first.
  if (region.kind == SubmapRegion::Kind::kBox)
    pageInBlocks(blockKeyOf(clampedKeyOf(region.min_map, params_.resolution_m)),
                 blockKeyOf(clampedKeyOf(region.max_map, params_.resolution_m)));
  else
    pageInAllBlocks();
  // The device copies of the region go back to the host (and are dropped) before reading.
  if (region.kind == SubmapRegion::Kind::kBox)
    backend_->cache().invalidate(blockKeyOf(clampedKeyOf(region.min_map, params_.resolution_m)),
                                 blockKeyOf(clampedKeyOf(region.max_map, params_.resolution_m)),
                                 blocks_);
  else
    backend_->cache().invalidateAll(blocks_);
  SubmapStats st;
  Map sub = copyRegion(region, backend, &st);
  if (region.kind == SubmapRegion::Kind::kBox)
    markScansTouching(region.min_map, region.max_map);
  else
    markScansWhere([&](const Eigen::Vector3d& origin_map, double reach_m) {
      return (origin_map - region.center_map).norm() + reach_m > region.radius_m;
    });
  ++revision_;
  clearCellsWhere(
      blocksOfRegion(blocks_, region, params_.resolution_m),
      [&](const VoxelKey& v) { return region.contains(centerOf(v)); }, &st.blocks_erased);
  st.seconds_total = secondsSince(t0);
  if (stats) *stats = st;
  return sub;
}

Map Map::extract(const Eigen::Vector3d& min_map, const Eigen::Vector3d& max_map, Backend backend,
                 SubmapStats* stats) const {
  return copyRegion(SubmapRegion::box(min_map, max_map), backend, stats);
}

Map Map::extractOutside(const Eigen::Vector3d& center_map, double radius_m, Backend backend,
                        SubmapStats* stats) const {
  return copyRegion(SubmapRegion::outsideSphere(center_map, radius_m), backend, stats);
}

Map Map::truncate(const Eigen::Vector3d& min_map, const Eigen::Vector3d& max_map, Backend backend,
                  SubmapStats* stats) {
  return moveOut(SubmapRegion::box(min_map, max_map), backend, stats);
}

Map Map::truncateOutside(const Eigen::Vector3d& center_map, double radius_m, Backend backend,
                         SubmapStats* stats) {
  return moveOut(SubmapRegion::outsideSphere(center_map, radius_m), backend, stats);
}

void Map::setRegion(const SubmapRegion& region) {
  region.validate();
  region_ = region;
}

SubmapStats Map::merge(const Map& sub, MergeMode mode,
                       const std::optional<Eigen::Isometry3d>& T_map_sub) {
  const auto t0 = Clock::now();
  if (&sub == this) throw InvalidArgument("cannot merge a map into itself");
  if (mode != MergeMode::kOverwrite && mode != MergeMode::kAdd)
    throw InvalidArgument("unknown merge mode");
  requireSameModel(params_, sub.params_);
  const Eigen::Isometry3d T = T_map_sub.value_or(Eigen::Isometry3d::Identity());
  requireRigidPose(T, "sub-map pose T_map_sub", 1e-6);
  const double res = params_.resolution_m;
  const Eigen::Vector3d t_vox = T.translation() / res;
  const Eigen::Vector3d shift_vox = t_vox.array().round();
  const bool exact_shift =
      (T.linear() - Eigen::Matrix3d::Identity()).cwiseAbs().maxCoeff() <= 1e-9 &&
      (t_vox - shift_vox).cwiseAbs().maxCoeff() <= 1e-6;

  SubmapStats st;
  const BlockView sub_view = sub.blockView();
  const KeyBounds sb = sub.bounds();
  if (sb.empty) {
    st.seconds_total = secondsSince(t0);
    return st;
  }
  // Where the merge writes, checked against the key range before anything changes.
  TargetBox box;
  if (exact_shift) {
    const int64_t sub_lo[3] = {sb.min.x, sb.min.y, sb.min.z};
    const int64_t sub_hi[3] = {sb.max.x, sb.max.y, sb.max.z};
    if (shift_vox.cwiseAbs().maxCoeff() > 4.0e9)
      throw InvalidArgument("sub-map pose moves it beyond the map's key range");
    for (int a = 0; a < 3; ++a) {
      box.lo[a] = sub_lo[a] + static_cast<int64_t>(shift_vox[a]);
      box.hi[a] = sub_hi[a] + static_cast<int64_t>(shift_vox[a]);
    }
  } else {
    const Eigen::Vector3d lo_sub = Eigen::Vector3d(sb.min.x, sb.min.y, sb.min.z) * res;
    const Eigen::Vector3d hi_sub =
        (Eigen::Vector3d(sb.max.x, sb.max.y, sb.max.z).array() + 1.0).matrix() * res;
    Eigen::Vector3d lo_map = Eigen::Vector3d::Constant(INFINITY);
    Eigen::Vector3d hi_map = -lo_map;
    for (int corner = 0; corner < 8; ++corner) {
      const Eigen::Vector3d p_sub((corner & 1) ? hi_sub.x() : lo_sub.x(),
                                  (corner & 2) ? hi_sub.y() : lo_sub.y(),
                                  (corner & 4) ? hi_sub.z() : lo_sub.z());
      const Eigen::Vector3d p_map = T * p_sub;
      lo_map = lo_map.cwiseMin(p_map);
      hi_map = hi_map.cwiseMax(p_map);
    }
    for (int a = 0; a < 3; ++a) {
      box.lo[a] = static_cast<int64_t>(std::floor(lo_map[a] / res));
      box.hi[a] = static_cast<int64_t>(std::floor(hi_map[a] / res));
    }
  }
  constexpr int64_t kKeyLimit = 2147483647LL - 4 * kBlockSize;
  for (int a = 0; a < 3; ++a)
    if (box.lo[a] < -kKeyLimit || box.hi[a] > kKeyLimit)
      throw InvalidArgument("sub-map pose moves it beyond the map's key range");

  // Checked: now the edit.
  const VoxelKey lo{static_cast<int32_t>(box.lo[0]), static_cast<int32_t>(box.lo[1]),
                    static_cast<int32_t>(box.lo[2])};
  const VoxelKey hi{static_cast<int32_t>(box.hi[0]), static_cast<int32_t>(box.hi[1]),
                    static_cast<int32_t>(box.hi[2])};
  pageInBlocks(blockKeyOf(lo), blockKeyOf(hi));
  backend_->cache().invalidate(blockKeyOf(lo), blockKeyOf(hi), blocks_);
  markScansTouching(Eigen::Vector3d(lo.x, lo.y, lo.z) * res,
                    (Eigen::Vector3d(hi.x, hi.y, hi.z).array() + 1.0).matrix() * res);
  ++revision_;
  std::unordered_set<BlockIndex> written;
  // Called for observed sub-map cells only, so every block it creates gets an observed cell.
  auto mergeInto = [&](const VoxelKey& v, const Cell& sub_cell) {
    const BlockIndex i = blocks_.findOrCreate(blockKeyOf(v));
    Cell& c = blocks_.block(i).cells[cellIndexOf(v)];
    const Cell value = combined(c, sub_cell, mode, model_);
    ++st.cells;
    if (value.log_odds_fx == c.log_odds_fx && value.hits == c.hits) return;
    const bool was_occupied = model_.state(c) == CellState::kOccupied;
    const bool state_changed = model_.stateDiffers(c, value);
    const CellState was = model_.state(c), is = model_.state(value);
    c = value;
    blocks_.masks(i).set(cellIndexOf(v), is);
    if (was != is) blocks_.noteMasksChanged(i, revision_);
    BlockMeta& meta = blocks_.meta(i);
    meta.changed_at = revision_;
    if (was_occupied != (model_.state(c) == CellState::kOccupied)) meta.occupied_at = revision_;
    if (state_changed) meta.state_at = revision_;
    written.insert(i);
  };

  if (exact_shift) {
    const int32_t dx = static_cast<int32_t>(shift_vox.x()),
                  dy = static_cast<int32_t>(shift_vox.y()),
                  dz = static_cast<int32_t>(shift_vox.z());
    sub_view.forEach([&](const BlockKey& key, const Block& block) {
      for (int c = 0; c < kCellsPerBlock; ++c) {
        if (!block.cells[c].observed()) continue;
        const VoxelKey v = voxelKeyOf(key, c);
        mergeInto(VoxelKey{v.x + dx, v.y + dy, v.z + dz}, block.cells[c]);
      }
    });
  } else {
    // Resampling: each map cell centre mapped back into the sub-map takes the cell there. A
    // sub-map block's cells are visited through the map cells its transformed bounds cover;
    // each map cell is merged once, from the block its centre maps back into.
    const Eigen::Isometry3d T_sub_map = T.inverse();
    const double edge_m = kBlockSize * res;
    sub_view.forEach([&](const BlockKey& key, const Block& block) {
      const Eigen::Vector3d lo_sub = Eigen::Vector3d(key.x, key.y, key.z) * edge_m;
      Eigen::Vector3d lo_map = Eigen::Vector3d::Constant(INFINITY);
      Eigen::Vector3d hi_map = -lo_map;
      for (int corner = 0; corner < 8; ++corner) {
        const Eigen::Vector3d p_sub =
            lo_sub + edge_m * Eigen::Vector3d((corner & 1) ? 1 : 0, (corner & 2) ? 1 : 0,
                                              (corner & 4) ? 1 : 0);
        const Eigen::Vector3d p_map = T * p_sub;
        lo_map = lo_map.cwiseMin(p_map);
        hi_map = hi_map.cwiseMax(p_map);
      }
      // One cell of margin against rounding at the bounds.
      const VoxelKey a = keyOf(lo_map), b = keyOf(hi_map);
      for (int32_t z = a.z - 1; z <= b.z + 1; ++z)
        for (int32_t y = a.y - 1; y <= b.y + 1; ++y)
          for (int32_t x = a.x - 1; x <= b.x + 1; ++x) {
            const VoxelKey v{x, y, z};
            const VoxelKey s = sub.keyOf(T_sub_map * centerOf(v));
            if (blockKeyOf(s) != key) continue;
            const Cell& sub_cell = block.cells[cellIndexOf(s)];
            if (sub_cell.observed()) mergeInto(v, sub_cell);
          }
    });
  }
  st.blocks = written.size();
  st.seconds_total = secondsSince(t0);
  return st;
}

}  // namespace fragg
