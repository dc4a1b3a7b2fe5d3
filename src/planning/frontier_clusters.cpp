#include "fragg_map/planning/frontier_clusters.h"

#include <fmt/format.h>

#include <Eigen/Eigenvalues>
#include <algorithm>
#include <array>
#include <cmath>
#include <unordered_map>

#include "fragg_map/errors.h"
#include "fragg_map/planning/frontier_cells.h"

namespace fragg::planning {

namespace {

// Frontier cells grouped by block: a 512-bit mask per block and the index of its first cell,
// so that a cell's index is its block's base plus its rank in the mask.
class CellIndex {
 public:
  explicit CellIndex(const std::vector<VoxelKey>& sorted) {
    for (size_t i = 0; i < sorted.size(); ++i) {
      const BlockKey b = blockKeyOf(sorted[i]);
      if (blocks_.empty() || blocks_.back().key != b) {
        blocks_.push_back({b, {}, {}, static_cast<uint32_t>(i)});
        lookup_.emplace(b, static_cast<uint32_t>(blocks_.size() - 1));
      }
      const int c = cellIndexOf(sorted[i]);
      blocks_.back().mask[c >> 6] |= uint64_t{1} << (c & 63);
    }
    for (Entry& e : blocks_) {
      uint32_t n = 0;
      for (int w = 0; w < 8; ++w) {
        e.before[w] = n;
        n += static_cast<uint32_t>(__builtin_popcountll(e.mask[w]));
      }
    }
  }
  struct Entry {
    BlockKey key;
    uint64_t mask[8];
    uint32_t before[8];  ///< cells in the words before
    uint32_t base;       ///< index of the block's first cell
  };
  const std::vector<Entry>& blocks() const { return blocks_; }
  /// Index of the entry for block `b`, -1 when it holds no cell.
  int64_t find(const BlockKey& b) const {
    const auto it = lookup_.find(b);
    return it == lookup_.end() ? -1 : int64_t{it->second};
  }
  /// Index of cell `c` of entry `e`, -1 when it is not a frontier cell.
  int64_t cell(const Entry& e, int c) const {
    const uint64_t word = e.mask[c >> 6], bit = uint64_t{1} << (c & 63);
    if (!(word & bit)) return -1;
    return int64_t{e.base} + e.before[c >> 6] + __builtin_popcountll(word & (bit - 1));
  }

 private:
  std::vector<Entry> blocks_;
  std::unordered_map<BlockKey, uint32_t, BlockKeyHash> lookup_;
};

uint32_t findRoot(std::vector<uint32_t>& parent, uint32_t i) {
  while (parent[i] != i) {
    parent[i] = parent[parent[i]];
    i = parent[i];
  }
  return i;
}

// 26-connected components of `sorted` (frontierOrder), each in that order, ordered by their
// first cell: union-find over the cells, each joined with its 13 neighbours that come before
// it (lexicographically negative offsets).
std::vector<std::vector<VoxelKey>> components(const std::vector<VoxelKey>& sorted,
                                              const QueryControl* control) {
  const CellIndex index(sorted);
  std::vector<uint32_t> parent(sorted.size());
  for (uint32_t i = 0; i < parent.size(); ++i) parent[i] = i;
  size_t done = 0;
  for (const CellIndex::Entry& e : index.blocks()) {
    if (++done % 4096 == 0) checkQuery(control, "frontier clusters");
    int64_t near[27];
    for (int dz = -1; dz <= 1; ++dz)
      for (int dy = -1; dy <= 1; ++dy)
        for (int dx = -1; dx <= 1; ++dx)
          near[(dz + 1) * 9 + (dy + 1) * 3 + dx + 1] =
              index.find({e.key.x + dx, e.key.y + dy, e.key.z + dz});
    for (int w = 0; w < 8; ++w)
      for (uint64_t bits = e.mask[w]; bits; bits &= bits - 1) {
        const int c = w * 64 + __builtin_ctzll(bits);
        const uint32_t self = static_cast<uint32_t>(index.cell(e, c));
        const int x = c & kBlockMask, y = (c >> kBlockBits) & kBlockMask, z = c >> (2 * kBlockBits);
        for (int o = 0; o < 13; ++o) {  // offsets before (0, 0, 0) in (dz, dy, dx) order
          const int dz = o / 9 - 1, dy = (o / 3) % 3 - 1, dx = o % 3 - 1;
          const int nx = x + dx, ny = y + dy, nz = z + dz;
          const int bx = nx < 0 ? 0 : (nx >= kBlockSize ? 2 : 1);
          const int by = ny < 0 ? 0 : (ny >= kBlockSize ? 2 : 1);
          const int bz = nz < 0 ? 0 : (nz >= kBlockSize ? 2 : 1);
          const int64_t nb = near[bz * 9 + by * 3 + bx];
          if (nb < 0) continue;
          const int nc = (nx & kBlockMask) | ((ny & kBlockMask) << kBlockBits) |
                         ((nz & kBlockMask) << (2 * kBlockBits));
          const int64_t other = index.cell(index.blocks()[nb], nc);
          if (other < 0) continue;
          const uint32_t ra = findRoot(parent, self), rb = findRoot(parent, uint32_t(other));
          if (ra != rb) parent[std::max(ra, rb)] = std::min(ra, rb);
        }
      }
  }
  // The root of a component is its smallest cell index, i.e. its first cell.
  std::vector<uint32_t> slot(sorted.size(), UINT32_MAX);
  std::vector<uint32_t> sizes;
  for (uint32_t i = 0; i < sorted.size(); ++i) {
    const uint32_t r = findRoot(parent, i);
    parent[i] = r;
    if (slot[r] == UINT32_MAX) {
      slot[r] = static_cast<uint32_t>(sizes.size());
      sizes.push_back(0);
    }
    ++sizes[slot[r]];
  }
  std::vector<std::vector<VoxelKey>> out(sizes.size());
  for (size_t c = 0; c < sizes.size(); ++c) out[c].reserve(sizes[c]);
  for (uint32_t i = 0; i < sorted.size(); ++i) out[slot[parent[i]]].push_back(sorted[i]);
  return out;
}

// Splits cells[begin, end) in place along their principal axis (at the mean) until each
// piece's bounding box edge is at most max_extent_cells (in cells); appends the pieces'
// ranges; each piece keeps the cells' order (a stable partition). Halves of more than
// kTaskCells cells are split as OpenMP tasks (the pieces come out in the same order).
constexpr size_t kTaskCells = size_t(1) << 15;

void splitToExtent(std::vector<VoxelKey>& cells, size_t begin, size_t end, double max_extent_cells,
                   std::vector<std::pair<size_t, size_t>>& out) {
  Eigen::Vector3d lo = Eigen::Vector3d::Constant(1e300), hi = -lo, mean = Eigen::Vector3d::Zero();
  for (size_t i = begin; i < end; ++i) {
    const Eigen::Vector3d p(cells[i].x, cells[i].y, cells[i].z);
    lo = lo.cwiseMin(p);
    hi = hi.cwiseMax(p);
    mean += p;
  }
  mean /= double(end - begin);
  if (max_extent_cells <= 0.0 || end - begin < 2 ||
      (hi - lo).maxCoeff() + 1.0 <= max_extent_cells + 1e-9) {
    out.emplace_back(begin, end);
    return;
  }
  Eigen::Matrix3d cov = Eigen::Matrix3d::Zero();
  for (size_t i = begin; i < end; ++i) {
    const Eigen::Vector3d d = Eigen::Vector3d(cells[i].x, cells[i].y, cells[i].z) - mean;
    cov += d * d.transpose();
  }
  const Eigen::SelfAdjointEigenSolver<Eigen::Matrix3d> eig(cov);
  const Eigen::Vector3d axis = eig.eigenvectors().col(2);  // largest eigenvalue
  const auto middle = std::stable_partition(
      cells.begin() + begin, cells.begin() + end,
      [&](const VoxelKey& k) { return axis.dot(Eigen::Vector3d(k.x, k.y, k.z) - mean) < 0.0; });
  const size_t mid = static_cast<size_t>(middle - cells.begin());
  if (mid == begin || mid == end) {  // cannot happen for >= 2 distinct cells; be safe
    out.emplace_back(begin, end);
    return;
  }
  if (end - begin < kTaskCells) {
    splitToExtent(cells, begin, mid, max_extent_cells, out);
    splitToExtent(cells, mid, end, max_extent_cells, out);
    return;
  }
  std::vector<std::pair<size_t, size_t>> left, right;
#pragma omp task default(shared)
  splitToExtent(cells, begin, mid, max_extent_cells, left);
#pragma omp task default(shared)
  splitToExtent(cells, mid, end, max_extent_cells, right);
#pragma omp taskwait
  out.insert(out.end(), left.begin(), left.end());
  out.insert(out.end(), right.begin(), right.end());
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
  // Unit vectors towards the 27 neighbours (the centre's is zero and never used).
  static const auto kUnit = [] {
    std::array<Eigen::Vector3d, 27> u;
    for (int i = 0; i < 27; ++i) {
      const Eigen::Vector3d d(i % 3 - 1, (i / 3) % 3 - 1, i / 9 - 1);
      u[i] = i == 13 ? d : Eigen::Vector3d(d.normalized());
    }
    return u;
  }();
  // Cells come grouped by block: the 27 blocks around are looked up once per block.
  BlockKey current{INT32_MIN, INT32_MIN, INT32_MIN};
  const Block* near[27] = {};
  for (const VoxelKey& k : c.cells) {
    const BlockKey b = blockKeyOf(k);
    if (b != current) {
      current = b;
      for (int i = 0; i < 27; ++i)
        near[i] = view.findBlock({b.x + i % 3 - 1, b.y + (i / 3) % 3 - 1, b.z + i / 9 - 1});
    }
    const Eigen::Vector3d p = map.centerOf(k);
    sum += p;
    c.min_m = c.min_m.cwiseMin(p - Eigen::Vector3d::Constant(half));
    c.max_m = c.max_m.cwiseMax(p + Eigen::Vector3d::Constant(half));
    const int x = k.x & kBlockMask, y = k.y & kBlockMask, z = k.z & kBlockMask;
    for (int dz = -1; dz <= 1; ++dz)
      for (int dy = -1; dy <= 1; ++dy)
        for (int dx = -1; dx <= 1; ++dx) {
          if (!dx && !dy && !dz) continue;
          const int nx = x + dx, ny = y + dy, nz = z + dz;
          const int bx = nx < 0 ? 0 : (nx >= kBlockSize ? 2 : 1);
          const int by = ny < 0 ? 0 : (ny >= kBlockSize ? 2 : 1);
          const int bz = nz < 0 ? 0 : (nz >= kBlockSize ? 2 : 1);
          const Block* nb = near[bz * 9 + by * 3 + bx];
          const int nc = (nx & kBlockMask) | ((ny & kBlockMask) << kBlockBits) |
                         ((nz & kBlockMask) << (2 * kBlockBits));
          if (!nb || map.state(nb->cells[nc]) == CellState::kUnknown)
            dir += kUnit[(dz + 1) * 9 + (dy + 1) * 3 + dx + 1];
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
                                                        const std::vector<VoxelKey>& cells,
                                                        const QueryControl* control) {
  checkQuery(control, "frontier clusters");
  std::vector<VoxelKey> sorted = cells;
  if (!std::is_sorted(sorted.begin(), sorted.end(), frontierOrder))
    std::sort(sorted.begin(), sorted.end(), frontierOrder);
  sorted.erase(std::unique(sorted.begin(), sorted.end()), sorted.end());
  std::vector<std::vector<VoxelKey>> comps = components(sorted, control);
  checkQuery(control, "frontier clusters");
  comps.erase(std::remove_if(comps.begin(), comps.end(),
                             [&](const auto& c) { return c.size() < options_.min_cells; }),
              comps.end());
  // stable_partition keeps the order on each side: pieces stay in frontierOrder. Components
  // are split as OpenMP tasks (large ones split their halves as tasks too).
  std::vector<std::vector<std::pair<size_t, size_t>>> ranges(comps.size());
  const double max_extent_cells = options_.max_extent_m / map.resolution();
#pragma omp parallel
#pragma omp single
  for (size_t i = 0; i < comps.size(); ++i) {
#pragma omp task default(shared) firstprivate(i)
    splitToExtent(comps[i], 0, comps[i].size(), max_extent_cells, ranges[i]);
  }
  std::vector<std::vector<VoxelKey>> pieces;
  for (size_t i = 0; i < comps.size(); ++i) {
    if (ranges[i].size() == 1) {
      pieces.push_back(std::move(comps[i]));
      continue;
    }
    for (const auto& [b, e] : ranges[i])
      pieces.emplace_back(comps[i].begin() + b, comps[i].begin() + e);
  }
  std::sort(pieces.begin(), pieces.end(),
            [](const auto& a, const auto& b) { return frontierOrder(a.front(), b.front()); });

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
    out.push_back(std::move(c));
  }
  const int64_t n = static_cast<int64_t>(out.size());
#pragma omp parallel for schedule(dynamic, 8)
  for (int64_t i = 0; i < n; ++i) describe(map, view, out[i]);
  previous_ = std::move(now);
  return out;
}

}  // namespace fragg::planning
