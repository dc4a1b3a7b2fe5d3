#include "fragg_map/planning/frontier_cells.h"

#include <fmt/format.h>
#include <omp.h>

#include <algorithm>
#include <array>
#include <cmath>

#include "fragg_map/errors.h"

namespace fragg::planning {

namespace {

// The 3x3x3 blocks around a block, index (dz + 1) * 9 + (dy + 1) * 3 + (dx + 1).
using Neighbourhood = std::array<const Block*, 27>;

Neighbourhood neighbourhoodOf(const BlockView& view, const BlockKey& b) {
  Neighbourhood n{};
  for (int dz = -1; dz <= 1; ++dz)
    for (int dy = -1; dy <= 1; ++dy)
      for (int dx = -1; dx <= 1; ++dx)
        n[(dz + 1) * 9 + (dy + 1) * 3 + (dx + 1)] = view.findBlock({b.x + dx, b.y + dy, b.z + dz});
  return n;
}

// Frontier rows of the centre block: bit x of rows[y + 8 z] is set for a free cell (x, y, z)
// with an unknown 26-neighbour. The unknown cells of the 10^3 cells around the block are
// gathered as rows of 10 bits (bit j: local x = j - 1), then each row of the block ORs the
// nine rows around it and spreads them by one cell along x.
std::array<uint8_t, kBlockSize * kBlockSize> frontierRows(const OccupancyModel& model,
                                                          const Neighbourhood& n) {
  constexpr int kSide = kBlockSize + 2;
  std::array<uint16_t, kSide * kSide> unknown{};  // index (z + 1) * kSide + (y + 1)
  std::array<uint8_t, kBlockSize * kBlockSize> free_rows{};
  for (int lz = -1; lz <= kBlockSize; ++lz) {
    const int bz = lz < 0 ? 0 : (lz >= kBlockSize ? 2 : 1);
    const int cz = lz & kBlockMask;
    for (int ly = -1; ly <= kBlockSize; ++ly) {
      const int by = ly < 0 ? 0 : (ly >= kBlockSize ? 2 : 1);
      const int cy = ly & kBlockMask;
      uint16_t row = 0;
      for (int lx = -1; lx <= kBlockSize; ++lx) {
        const int bx = lx < 0 ? 0 : (lx >= kBlockSize ? 2 : 1);
        const Block* block = n[bz * 9 + by * 3 + bx];
        if (!block) {
          row |= uint16_t(1u << (lx + 1));
          continue;
        }
        const int c = (lx & kBlockMask) | (cy << kBlockBits) | (cz << (2 * kBlockBits));
        const CellState s = model.state(block->cells[c]);
        if (s == CellState::kUnknown) row |= uint16_t(1u << (lx + 1));
        if (s == CellState::kFree && bx == 1 && by == 1 && bz == 1)
          free_rows[ly + kBlockSize * lz] |= uint8_t(1u << lx);
      }
      unknown[(lz + 1) * kSide + (ly + 1)] = row;
    }
  }
  std::array<uint8_t, kBlockSize * kBlockSize> rows{};
  for (int z = 0; z < kBlockSize; ++z)
    for (int y = 0; y < kBlockSize; ++y) {
      const uint8_t f = free_rows[y + kBlockSize * z];
      if (!f) continue;
      uint32_t m = 0;
      for (int dz = 0; dz < 3; ++dz)
        for (int dy = 0; dy < 3; ++dy) m |= unknown[(z + dz) * kSide + (y + dy)];
      // Bit x of `spread`: any of local x - 1, x, x + 1 (bits x, x + 1, x + 2 of m) unknown.
      const uint32_t spread = m | (m >> 1) | (m >> 2);
      rows[y + kBlockSize * z] = static_cast<uint8_t>(f & spread);
    }
  return rows;
}

bool obstacleWithin(const Map& map, const BlockView& view, const VoxelKey& key, double distance_m) {
  const double res = map.resolution();
  const int r = static_cast<int>(std::ceil(distance_m / res));
  const double limit_sq = (distance_m / res) * (distance_m / res);  // in cells^2
  for (int dz = -r; dz <= r; ++dz)
    for (int dy = -r; dy <= r; ++dy)
      for (int dx = -r; dx <= r; ++dx) {
        if (double(dx * dx + dy * dy + dz * dz) >= limit_sq) continue;
        const Cell* c = view.findCell({key.x + dx, key.y + dy, key.z + dz});
        if (c && map.state(*c) == CellState::kOccupied) return true;
      }
  return false;
}

}  // namespace

void FrontierFilter::validate() const {
  if (use_box) {
    if (!box_min_m.allFinite() || !box_max_m.allFinite())
      throw InvalidArgument("frontier box corners must be finite");
    if ((box_min_m.array() > box_max_m.array()).any())
      throw InvalidArgument("frontier box min corner must not exceed the max corner");
  }
  if (use_height) {
    if (!std::isfinite(min_z_m) || !std::isfinite(max_z_m))
      throw InvalidArgument("frontier height band must be finite");
    if (min_z_m > max_z_m)
      throw InvalidArgument(
          fmt::format("frontier height band is inverted ({} > {})", min_z_m, max_z_m));
  }
  if (!std::isfinite(min_obstacle_distance_m) || min_obstacle_distance_m < 0.0)
    throw InvalidArgument(fmt::format("frontier obstacle distance must be finite and >= 0, got {}",
                                      min_obstacle_distance_m));
}

bool FrontierFilter::keeps(const Map& map, const BlockView& view, const VoxelKey& key) const {
  const Eigen::Vector3d c = map.centerOf(key);
  if (use_box && ((c.array() < box_min_m.array()).any() || (c.array() > box_max_m.array()).any()))
    return false;
  if (use_height && (c.z() < min_z_m || c.z() > max_z_m)) return false;
  if (min_obstacle_distance_m > 0.0 && obstacleWithin(map, view, key, min_obstacle_distance_m))
    return false;
  return true;
}

bool blockOrder(const BlockKey& a, const BlockKey& b) {
  if (a.z != b.z) return a.z < b.z;
  if (a.y != b.y) return a.y < b.y;
  return a.x < b.x;
}

bool frontierOrder(const VoxelKey& a, const VoxelKey& b) {
  const BlockKey ba = blockKeyOf(a), bb = blockKeyOf(b);
  if (ba != bb) return blockOrder(ba, bb);
  return cellIndexOf(a) < cellIndexOf(b);
}

std::vector<uint16_t> frontierCellsOfBlock(const Map& map, const BlockView& view,
                                           const BlockKey& block, const FrontierFilter& filter) {
  std::vector<uint16_t> cells;
  if (!view.findBlock(block)) return cells;
  const auto rows = frontierRows(map.model(), neighbourhoodOf(view, block));
  for (int r = 0; r < kBlockSize * kBlockSize; ++r) {
    for (uint32_t bits = rows[r]; bits; bits &= bits - 1) {
      const int x = __builtin_ctz(bits);
      const uint16_t index = static_cast<uint16_t>(r * kBlockSize + x);
      if (filter.any() && !filter.keeps(map, view, voxelKeyOf(block, index))) continue;
      cells.push_back(index);
    }
  }
  return cells;
}

std::vector<VoxelKey> findFrontierCells(const Map& map, const FrontierFilter& filter, int threads) {
  filter.validate();
  if (threads < 0) throw InvalidArgument(fmt::format("threads must be >= 0, got {}", threads));
  const BlockView view = map.blockView();
  std::vector<BlockRef> blocks = view.all();
  if (filter.use_box) {  // blocks wholly outside the box hold no kept cell
    const BlockKey lo = blockKeyOf(map.keyOf(filter.box_min_m));
    const BlockKey hi = blockKeyOf(map.keyOf(filter.box_max_m));
    blocks = view.in(lo, hi);
  }
  // Blocks in order, cells in index order within each: the result needs no sort of its own.
  std::sort(blocks.begin(), blocks.end(),
            [](const BlockRef& a, const BlockRef& b) { return blockOrder(a.key, b.key); });
  const int n_threads = threads > 0 ? threads : omp_get_max_threads();
  std::vector<std::vector<uint16_t>> found(blocks.size());
  const int64_t n = static_cast<int64_t>(blocks.size());
#pragma omp parallel for schedule(dynamic, 64) num_threads(n_threads)
  for (int64_t i = 0; i < n; ++i) found[i] = frontierCellsOfBlock(map, view, blocks[i].key, filter);
  size_t total = 0;
  for (const auto& f : found) total += f.size();
  std::vector<VoxelKey> cells;
  cells.reserve(total);
  for (size_t i = 0; i < blocks.size(); ++i)
    for (uint16_t c : found[i]) cells.push_back(voxelKeyOf(blocks[i].key, c));
  return cells;
}

}  // namespace fragg::planning
