// Map -> octomap::OcTree -> .bt file.
#include <fmt/format.h>

#include <sstream>

#include "fragg_map/atomic_file.h"
#include "fragg_map/errors.h"
#include "fragg_map/interop/octomap_io.h"

namespace fragg {
namespace {

bool inOctomapRange(const VoxelKey& v) {
  auto in = [](int32_t k) { return k >= kOctomapMinKey && k <= kOctomapMaxKey; };
  return in(v.x) && in(v.y) && in(v.z);
}

}  // namespace

std::unique_ptr<octomap::OcTree> toOcTree(const Map& map) {
  auto tree = std::make_unique<octomap::OcTree>(map.resolution());
  const OccupancyParams& occupancy = map.params().occupancy;
  tree->setProbHit(occupancy.prob_hit);
  tree->setProbMiss(occupancy.prob_miss);
  tree->setClampingThresMin(occupancy.clamp_min);
  tree->setClampingThresMax(occupancy.clamp_max);
  tree->setOccupancyThres(0.5);

  map.forEachBlock([&](const BlockKey& block_key, const Block& block) {
    for (int i = 0; i < kCellsPerBlock; ++i) {
      const Cell& cell = block.cells[i];
      if (!cell.observed()) continue;
      const VoxelKey v = voxelKeyOf(block_key, i);
      if (!inOctomapRange(v)) {
        const Eigen::Vector3d p = map.centerOf(v);
        throw IoError(fmt::format(
            "cannot export to OctoMap: cell ({}, {}, {}) at ({:.3f}, {:.3f}, {:.3f}) m lies "
            "outside OctoMap's 16-bit key range ([{}, {}] voxels per axis, +-{:.1f} m at {} m)",
            v.x, v.y, v.z, p.x(), p.y(), p.z(), kOctomapMinKey, kOctomapMaxKey,
            -kOctomapMinKey * map.resolution(), map.resolution()));
      }
      const octomap::OcTreeKey key(static_cast<octomap::key_type>(v.x - kOctomapMinKey),
                                   static_cast<octomap::key_type>(v.y - kOctomapMinKey),
                                   static_cast<octomap::key_type>(v.z - kOctomapMinKey));
      const float log_odds = static_cast<float>(cell.log_odds_fx) / kLogOddsScale;
      // setNodeValue clamps to the tree's thresholds; keep the cell's exact value instead.
      octomap::OcTreeNode* node = tree->setNodeValue(key, log_odds, /*lazy_eval=*/true);
      node->setLogOdds(log_odds);
    }
  });
  tree->updateInnerOccupancy();
  return tree;
}

void exportOctomap(const Map& map, const std::string& path_bt) {
  std::unique_ptr<octomap::OcTree> tree = toOcTree(map);
  // What OcTree::writeBinary does, without liboctomap's debug lines on stderr.
  tree->toMaxLikelihood();
  tree->prune();
  std::ostringstream buffer(std::ios::out | std::ios::binary);
  buffer << "# Octomap OcTree binary file\n"
         << "# (feel free to add / change comments, but leave the first line as it is!)\n#\n"
         << "id " << tree->getTreeType() << "\n"
         << "size " << tree->size() << "\n"
         << "res " << tree->getResolution() << "\n"
         << "data\n";
  tree->writeBinaryData(buffer);
  if (!buffer) throw IoError(fmt::format("cannot write {}: cannot serialise the tree", path_bt));
  tree.reset();  // the serialised copy is all that is needed from here on
  AtomicFile file(path_bt);
  file.write(buffer.str());
  file.commit();
}

std::string octomapFullData(const Map& map, bool prune) {
  std::unique_ptr<octomap::OcTree> tree = toOcTree(map);
  if (prune) tree->prune();
  std::ostringstream buffer(std::ios::out | std::ios::binary);
  tree->writeData(buffer);
  if (!buffer) throw IoError("cannot serialise the map as a full OctoMap tree");
  return buffer.str();
}

void exportOctomapFull(const Map& map, const std::string& path_ot, bool prune) {
  std::unique_ptr<octomap::OcTree> tree = toOcTree(map);
  if (prune) tree->prune();
  // What AbstractOcTree::write does, without liboctomap's debug lines on stderr.
  std::ostringstream buffer(std::ios::out | std::ios::binary);
  buffer << "# Octomap OcTree file\n"
         << "# (feel free to add / change comments, but leave the first line as it is!)\n#\n"
         << "id " << tree->getTreeType() << "\n"
         << "size " << tree->size() << "\n"
         << "res " << tree->getResolution() << "\n"
         << "data\n";
  tree->writeData(buffer);
  if (!buffer) throw IoError(fmt::format("cannot write {}: cannot serialise the tree", path_ot));
  tree.reset();
  AtomicFile file(path_ot);
  file.write(buffer.str());
  file.commit();
}

}  // namespace fragg
