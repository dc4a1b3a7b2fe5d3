// OctoMap as the reference: the same scans through octomap::OcTree::insertPointCloud, and a
// cell-by-cell comparison with a fragg map (OctoMap's rule: observed, occupied iff p > 0.5), of
// the states and of the log-odds values.
#pragma once

#include <octomap/octomap.h>

#include <algorithm>
#include <cmath>
#include <cstdint>
#include <unordered_map>
#include <vector>

#include "fragg_map/io/dataset.h"
#include "fragg_map/map.h"

namespace fragg::test {

/// Log-odds of a cell in both maps agree within this: fragg keeps them in 1/1024 units, each
/// update rounded to them (at most 1/2048 off), and a cell takes at most one update a scan.
constexpr double kLogOddsTolerance = 0.01;

struct Agreement {
  uint64_t both = 0, both_same = 0;  ///< cells known to both maps, and of those the same state
  uint64_t only_fragg = 0, only_octomap = 0;
  /// Cells known to both whose log-odds agree within kLogOddsTolerance, and the largest
  /// difference seen (compareWithOctomap only: a .bt file keeps no log-odds worth comparing).
  uint64_t both_same_log_odds = 0;
  double max_log_odds_diff = 0.0;
  double bothRatio() const { return both ? double(both_same) / both : 0.0; }
  double logOddsRatio() const { return both ? double(both_same_log_odds) / both : 0.0; }
  double eitherRatio() const {
    const uint64_t either = both + only_fragg + only_octomap;
    return either ? double(both_same) / either : 0.0;
  }
};

inline void insertIntoOctomap(octomap::OcTree& tree, const Scan& scan, double max_range_m) {
  octomap::Pointcloud pc;
  pc.reserve(scan.cloud.size());
  for (const auto& p : scan.cloud.points_S) {
    if (!p.allFinite() || p.squaredNorm() == 0.f) continue;
    const Eigen::Vector3d q = scan.T_map_sensor * p.cast<double>();
    pc.push_back(static_cast<float>(q.x()), static_cast<float>(q.y()), static_cast<float>(q.z()));
  }
  const Eigen::Vector3d o = scan.T_map_sensor.translation();
  tree.insertPointCloud(pc, octomap::point3d(o.x(), o.y(), o.z()), max_range_m);
}

/// octomap_server's insertScan: points whose `ground` flag is set only clear (the ray's cells,
/// not the point's), the others as insertPointCloud inserts them; a cell hit in the scan is not
/// also cleared.
inline void insertLikeOctomapServer(octomap::OcTree& tree, const Scan& scan,
                                    const std::vector<uint8_t>& ground, double max_range_m) {
  const Eigen::Vector3d o = scan.T_map_sensor.translation();
  const octomap::point3d origin(o.x(), o.y(), o.z());
  octomap::KeySet free_cells, occupied_cells;
  octomap::KeyRay ray;
  for (size_t i = 0; i < scan.cloud.size(); ++i) {
    const Eigen::Vector3f& p = scan.cloud.points_S[i];
    if (!p.allFinite() || p.squaredNorm() == 0.f) continue;
    const Eigen::Vector3d q = scan.T_map_sensor * p.cast<double>();
    octomap::point3d end(static_cast<float>(q.x()), static_cast<float>(q.y()),
                         static_cast<float>(q.z()));
    const bool far = (end - origin).norm() > max_range_m;
    if (far) end = origin + (end - origin).normalized() * max_range_m;
    if (tree.computeRayKeys(origin, end, ray)) free_cells.insert(ray.begin(), ray.end());
    octomap::OcTreeKey key;
    if (!ground[i] && !far && tree.coordToKeyChecked(end, key)) occupied_cells.insert(key);
  }
  for (const octomap::OcTreeKey& k : free_cells)
    if (!occupied_cells.count(k)) tree.updateNode(k, false);
  for (const octomap::OcTreeKey& k : occupied_cells) tree.updateNode(k, true);
}

inline octomap::OcTree octomapWithParamsOf(const MapParams& p) {
  octomap::OcTree tree(p.resolution_m);
  tree.setProbHit(p.occupancy.prob_hit);
  tree.setProbMiss(p.occupancy.prob_miss);
  tree.setClampingThresMin(p.occupancy.clamp_min);
  tree.setClampingThresMax(p.occupancy.clamp_max);
  tree.setOccupancyThres(0.5);
  return tree;
}

struct VoxelKeyHasher {
  size_t operator()(const VoxelKey& k) const { return VoxelKeyHash()(k); }
};
struct OctoLeaf {
  bool occupied;  ///< OctoMap's own occupancy test
  float log_odds;
};
using LeafStates = std::unordered_map<VoxelKey, OctoLeaf, VoxelKeyHasher>;

/// Every voxel an OcTree knows (coarser leaves expanded), with OctoMap's own occupancy test.
inline LeafStates leafStates(const octomap::OcTree& tree) {
  LeafStates states;
  const int depth = static_cast<int>(tree.getTreeDepth());
  for (auto it = tree.begin_leafs(), end = tree.end_leafs(); it != end; ++it) {
    const int span = 1 << (depth - static_cast<int>(it.getDepth()));
    const octomap::OcTreeKey k = it.getIndexKey();  // smallest key of the leaf's cube
    const OctoLeaf leaf{tree.isNodeOccupied(*it), it->getLogOdds()};
    for (int dx = 0; dx < span; ++dx)
      for (int dy = 0; dy < span; ++dy)
        for (int dz = 0; dz < span; ++dz)
          states[VoxelKey{int(k[0]) - 32768 + dx, int(k[1]) - 32768 + dy, int(k[2]) - 32768 + dz}] =
              leaf;
  }
  return states;
}

/// Compares every cell either map knows (fragg: observed, occupied iff log-odds > 0).
inline Agreement compareWithOctomap(const Map& map, const octomap::OcTree& tree) {
  LeafStates octo = leafStates(tree);
  Agreement a;
  map.forEachBlock([&](const BlockKey& key, const Block& b) {
    for (int c = 0; c < kCellsPerBlock; ++c) {
      if (!b.cells[c].observed()) continue;
      const bool occupied = b.cells[c].log_odds_fx > 0;
      auto it = octo.find(voxelKeyOf(key, c));
      if (it == octo.end()) {
        ++a.only_fragg;
        continue;
      }
      ++a.both;
      a.both_same += it->second.occupied == occupied ? 1 : 0;
      const double diff =
          std::abs(double(b.cells[c].log_odds_fx) / kLogOddsScale - double(it->second.log_odds));
      a.both_same_log_odds += diff <= kLogOddsTolerance ? 1 : 0;
      a.max_log_odds_diff = std::max(a.max_log_odds_diff, diff);
      octo.erase(it);
    }
  });
  a.only_octomap = octo.size();
  return a;
}

/// The same comparison of states between two OcTrees (`ours` plays fragg's part).
inline Agreement compareTrees(const octomap::OcTree& ours, const octomap::OcTree& reference) {
  LeafStates ref = leafStates(reference);
  Agreement a;
  for (const auto& [key, leaf] : leafStates(ours)) {
    auto it = ref.find(key);
    if (it == ref.end()) {
      ++a.only_fragg;
      continue;
    }
    ++a.both;
    a.both_same += it->second.occupied == leaf.occupied ? 1 : 0;
    ref.erase(it);
  }
  a.only_octomap = ref.size();
  return a;
}

}  // namespace fragg::test
