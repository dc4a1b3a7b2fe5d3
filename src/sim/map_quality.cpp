#include "fragg_map/sim/map_quality.h"

#include <algorithm>
#include <cmath>
#include <vector>

#include "fragg_map/geometry/triangle_queries.h"

namespace fragg::sim {
namespace {

// Cell lookups with the last block remembered (voxels are visited in coherent order).
class CellLookup {
 public:
  explicit CellLookup(const BlockView& blocks) : blocks_(blocks) {}
  const Cell* find(const VoxelKey& k) {
    const BlockKey b = blockKeyOf(k);
    if (!valid_ || b != last_key_) {
      last_key_ = b;
      last_ = blocks_.findBlock(b);
      valid_ = true;
    }
    return last_ ? &last_->cells[cellIndexOf(k)] : nullptr;
  }
  bool observedAround(const VoxelKey& k) {
    const Cell* c = find(k);
    if (c && c->observed()) return true;
    for (int dz = -1; dz <= 1; ++dz)
      for (int dy = -1; dy <= 1; ++dy)
        for (int dx = -1; dx <= 1; ++dx) {
          if (!dx && !dy && !dz) continue;
          const Cell* n = find({k.x + dx, k.y + dy, k.z + dz});
          if (n && n->observed()) return true;
        }
    return false;
  }

 private:
  const BlockView& blocks_;
  BlockKey last_key_;
  const Block* last_ = nullptr;
  bool valid_ = false;
};

bool lessKey(const VoxelKey& a, const VoxelKey& b) {
  if (a.x != b.x) return a.x < b.x;
  if (a.y != b.y) return a.y < b.y;
  return a.z < b.z;
}

}  // namespace

MapQuality evaluateMapQuality(const Map& map, const geometry::MeshBvh& scene,
                              const MapQualityOptions& options) {
  MapQuality q;
  const double res = map.resolution();
  q.resolution_m = res;
  const float near_m = static_cast<float>(std::sqrt(3.0) / 2.0 * res);
  const BlockView blocks = map.blockView();
  const Eigen::AlignedBox3f bounds = scene.bounds();

  auto occupied = [&](const Cell& c) {
    return options.octomap_threshold ? c.log_odds_fx >= 0 : map.state(c) == CellState::kOccupied;
  };
  auto isFree = [&](const Cell& c) {
    return options.octomap_threshold ? c.log_odds_fx < 0 : map.state(c) == CellState::kFree;
  };

  // 1. Every known cell: precision (occupied) and free-space errors (free).
  const std::vector<BlockRef> all = blocks.all();
  uint64_t occ = 0, occ_near = 0, free = 0, inside = 0, deep = 0;
#pragma omp parallel for schedule(dynamic, 16) reduction(+ : occ, occ_near, free, inside, deep)
  for (size_t n = 0; n < all.size(); ++n) {
    const BlockKey bk = all[n].key;
    const Block& block = *all[n].block;
    for (int ci = 0; ci < kCellsPerBlock; ++ci) {
      const Cell& c = block.cells[ci];
      if (!c.observed()) continue;
      const Eigen::Vector3f p = map.centerOf(voxelKeyOf(bk, ci)).cast<float>();
      if (occupied(c)) {
        ++occ;
        if (scene.withinDistance(p, near_m)) ++occ_near;
      } else if (isFree(c)) {
        ++free;
        if (bounds.contains(p) && scene.inside(p)) {
          ++inside;
          if (!scene.withinDistance(p, near_m)) ++deep;
        }
      }
    }
  }
  q.occupied = occ;
  q.occupied_near_surface = occ_near;
  q.free = free;
  q.free_inside = inside;
  q.free_inside_deep = deep;

  // 2. Surface voxels in the observed region, per triangle, then merged without duplicates.
  const geometry::TriangleMesh& mesh = scene.mesh();
  std::vector<VoxelKey> surface;
  const Eigen::Vector3d half = Eigen::Vector3d::Constant(0.5 * res);
#pragma omp parallel
  {
    std::vector<VoxelKey> local;
    CellLookup lookup(blocks);
#pragma omp for schedule(dynamic, 64)
    for (size_t t = 0; t < mesh.triangles.size(); ++t) {
      const Eigen::Vector3i& tri = mesh.triangles[t];
      const Eigen::Vector3d a = mesh.vertices_m[tri[0]].cast<double>();
      const Eigen::Vector3d b = mesh.vertices_m[tri[1]].cast<double>();
      const Eigen::Vector3d c = mesh.vertices_m[tri[2]].cast<double>();
      const Eigen::Vector3d lo = a.cwiseMin(b).cwiseMin(c), hi = a.cwiseMax(b).cwiseMax(c);
      const VoxelKey k0 = map.keyOf(lo), k1 = map.keyOf(hi);
      // Only voxels in an existing block or next to one can be in the observed region: visit
      // the blocks near the triangle, each grown by one voxel on every side.
      const std::vector<BlockRef> near_blocks = blocks.in(
          blockKeyOf({k0.x - 1, k0.y - 1, k0.z - 1}), blockKeyOf({k1.x + 1, k1.y + 1, k1.z + 1}));
      for (const BlockRef& near : near_blocks) {
        const BlockKey bk = near.key;
        const VoxelKey b0{std::max(k0.x, bk.x * kBlockSize - 1),
                          std::max(k0.y, bk.y * kBlockSize - 1),
                          std::max(k0.z, bk.z * kBlockSize - 1)};
        const VoxelKey b1{std::min(k1.x, bk.x * kBlockSize + kBlockSize),
                          std::min(k1.y, bk.y * kBlockSize + kBlockSize),
                          std::min(k1.z, bk.z * kBlockSize + kBlockSize)};
        if (b0.x > b1.x || b0.y > b1.y || b0.z > b1.z) continue;
        const Eigen::Vector3d box_lo = Eigen::Vector3d(b0.x, b0.y, b0.z) * res;
        const Eigen::Vector3d box_hi = Eigen::Vector3d(b1.x + 1, b1.y + 1, b1.z + 1) * res;
        if (!geometry::triangleBoxOverlap(0.5 * (box_lo + box_hi), 0.5 * (box_hi - box_lo), a, b,
                                          c))
          continue;
        for (int32_t z = b0.z; z <= b1.z; ++z)
          for (int32_t y = b0.y; y <= b1.y; ++y)
            for (int32_t x = b0.x; x <= b1.x; ++x) {
              const VoxelKey k{x, y, z};
              if (!geometry::triangleBoxOverlap(map.centerOf(k), half, a, b, c)) continue;
              if (lookup.observedAround(k)) local.push_back(k);
            }
      }
    }
#pragma omp critical
    surface.insert(surface.end(), local.begin(), local.end());
  }
  std::sort(surface.begin(), surface.end(), lessKey);
  surface.erase(std::unique(surface.begin(), surface.end()), surface.end());
  q.surface_observed = surface.size();
  for (const VoxelKey& k : surface) {
    const Cell* c = map.findCell(k);
    if (!c || !c->observed()) continue;
    ++q.surface_known;
    if (occupied(*c)) ++q.surface_observed_occupied;
  }
  return q;
}

}  // namespace fragg::sim
