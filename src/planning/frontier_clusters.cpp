#include "fragg_map/planning/frontier_clusters.h"

#include <fmt/format.h>

#include <Eigen/Eigenvalues>
#include <algorithm>
#include <cmath>
#include <unordered_set>

#include "fragg_map/errors.h"
#include "fragg_map/planning/frontier_cells.h"

namespace fragg::planning {

namespace {

using KeySet = std::unordered_set<VoxelKey, VoxelKeyHash>;

std::vector<std::vector<VoxelKey>> components(const std::vector<VoxelKey>& cells) {
  KeySet left(cells.begin(), cells.end());
  std::vector<std::vector<VoxelKey>> out;
  for (const VoxelKey& seed : cells) {  // sorted input: deterministic components
    if (!left.erase(seed)) continue;
    std::vector<VoxelKey> comp{seed};
    for (size_t i = 0; i < comp.size(); ++i) {
      const VoxelKey k = comp[i];
      for (int dz = -1; dz <= 1; ++dz)
        for (int dy = -1; dy <= 1; ++dy)
          for (int dx = -1; dx <= 1; ++dx) {
            const VoxelKey n{k.x + dx, k.y + dy, k.z + dz};
            if (left.erase(n)) comp.push_back(n);
          }
    }
    std::sort(comp.begin(), comp.end(), keyLess);
    out.push_back(std::move(comp));
  }
  return out;
}

// Splits `cells` along their principal axis until each piece's bounding box edge is at most
// max_extent_cells (in cells).
void splitToExtent(const std::vector<VoxelKey>& cells, double max_extent_cells,
                   std::vector<std::vector<VoxelKey>>& out) {
  Eigen::Vector3d lo = Eigen::Vector3d::Constant(1e300), hi = -lo, mean = Eigen::Vector3d::Zero();
  for (const VoxelKey& k : cells) {
    const Eigen::Vector3d p(k.x, k.y, k.z);
    lo = lo.cwiseMin(p);
    hi = hi.cwiseMax(p);
    mean += p;
  }
  mean /= double(cells.size());
  if (max_extent_cells <= 0.0 || cells.size() < 2 ||
      (hi - lo).maxCoeff() + 1.0 <= max_extent_cells + 1e-9) {
    out.push_back(cells);
    return;
  }
  Eigen::Matrix3d cov = Eigen::Matrix3d::Zero();
  for (const VoxelKey& k : cells) {
    const Eigen::Vector3d d = Eigen::Vector3d(k.x, k.y, k.z) - mean;
    cov += d * d.transpose();
  }
  const Eigen::SelfAdjointEigenSolver<Eigen::Matrix3d> eig(cov);
  const Eigen::Vector3d axis = eig.eigenvectors().col(2);  // largest eigenvalue
  std::vector<VoxelKey> a, b;
  for (const VoxelKey& k : cells)
    (axis.dot(Eigen::Vector3d(k.x, k.y, k.z) - mean) < 0.0 ? a : b).push_back(k);
  if (a.empty() || b.empty()) {  // cannot happen for >= 2 distinct cells; be safe
    out.push_back(cells);
    return;
  }
  splitToExtent(a, max_extent_cells, out);
  splitToExtent(b, max_extent_cells, out);
}

uint64_t hashCells(const std::vector<VoxelKey>& cells) {
  uint64_t h = 1469598103934665603ULL;
  for (const VoxelKey& k : cells) {
    h ^= VoxelKeyHash()(k);
    h *= 1099511628211ULL;
  }
  return h ^ cells.size();
}

void describe(const Map& map, const BlockView& view, FrontierCluster& c) {
  const double half = 0.5 * map.resolution();
  Eigen::Vector3d sum = Eigen::Vector3d::Zero(), dir = Eigen::Vector3d::Zero();
  c.min_m = Eigen::Vector3d::Constant(1e300);
  c.max_m = -c.min_m;
  for (const VoxelKey& k : c.cells) {
    const Eigen::Vector3d p = map.centerOf(k);
    sum += p;
    c.min_m = c.min_m.cwiseMin(p - Eigen::Vector3d::Constant(half));
    c.max_m = c.max_m.cwiseMax(p + Eigen::Vector3d::Constant(half));
    for (int dz = -1; dz <= 1; ++dz)
      for (int dy = -1; dy <= 1; ++dy)
        for (int dx = -1; dx <= 1; ++dx) {
          if (!dx && !dy && !dz) continue;
          const Cell* n = view.findCell({k.x + dx, k.y + dy, k.z + dz});
          if (!n || map.state(*n) == CellState::kUnknown)
            dir += Eigen::Vector3d(dx, dy, dz).normalized();
        }
  }
  c.centroid_m = sum / double(c.cells.size());
  const double norm = dir.norm();
  c.direction = norm > 1e-9 ? Eigen::Vector3d(dir / norm) : Eigen::Vector3d::Zero();
}

}  // namespace

void ClusterOptions::validate() const {
  if (min_cells == 0) throw InvalidArgument("minimum cluster size must be >= 1");
  if (!std::isfinite(max_extent_m) || max_extent_m < 0.0)
    throw InvalidArgument(
        fmt::format("maximum cluster extent must be finite and >= 0, got {}", max_extent_m));
}

FrontierClusterer::FrontierClusterer(const ClusterOptions& options) : options_(options) {
  options_.validate();
}

std::vector<FrontierCluster> FrontierClusterer::cluster(const Map& map,
                                                        const std::vector<VoxelKey>& cells) {
  std::vector<VoxelKey> sorted = cells;
  std::sort(sorted.begin(), sorted.end(), keyLess);
  std::vector<std::vector<VoxelKey>> pieces;
  for (const auto& comp : components(sorted)) {
    if (comp.size() < options_.min_cells) continue;
    splitToExtent(comp, options_.max_extent_m / map.resolution(), pieces);
  }
  for (auto& p : pieces) std::sort(p.begin(), p.end(), keyLess);
  std::sort(pieces.begin(), pieces.end(),
            [](const auto& a, const auto& b) { return keyLess(a.front(), b.front()); });

  const BlockView view = map.blockView();
  std::unordered_map<uint64_t, uint64_t> now;
  std::vector<FrontierCluster> out;
  out.reserve(pieces.size());
  for (auto& p : pieces) {
    FrontierCluster c;
    const uint64_t h = hashCells(p);
    const auto it = previous_.find(h);
    c.id = (it != previous_.end() && !now.count(h)) ? it->second : next_id_++;
    now[h] = c.id;
    c.cells = std::move(p);
    describe(map, view, c);
    out.push_back(std::move(c));
  }
  previous_ = std::move(now);
  return out;
}

}  // namespace fragg::planning
