#include "fragg_map/planning/coarse_map.h"

#include <fmt/format.h>

#include <cmath>
#include <vector>

#include "fragg_map/errors.h"
#include "fragg_map/state_masks.h"

namespace fragg::planning {

namespace {

/// floor(v / cells) for cells a power of two (arithmetic shift: right for negative keys).
int32_t coarseOf(int32_t v, int shift) { return v >> shift; }

}  // namespace

bool validCoarseCells(int cells) { return cells == 1 || cells == 2 || cells == 4 || cells == 8; }

namespace {

// The coarse map of the blocks in [lo, hi] (block keys).
Map coarseOfBlocks(const Map& map, int cells, const BlockKey& lo, const BlockKey& hi,
                   const QueryControl* control) {
  if (!validCoarseCells(cells))
    throw InvalidArgument(
        fmt::format("coarse frontier cells must be 1, 2, 4 or 8 map cells, got {}", cells));
  const int shift = cells == 1 ? 0 : (cells == 2 ? 1 : (cells == 4 ? 2 : 3));
  MapParams params = map.params();
  params.resolution_m = map.resolution() * cells;
  params.backend = Backend::kCpu;
  params.scans.keep = false;
  Map coarse(params);
  const OccupancyModel& model = map.model();
  const Cell free_cell{0, model.min_fx}, occupied_cell{0, model.max_fx};
  if (model.state(free_cell) != CellState::kFree ||
      model.state(occupied_cell) != CellState::kOccupied)
    throw InvalidArgument(
        "coarse map: the occupancy model's clamps lie inside its unknown band (a coarse cell "
        "could not be written free or occupied)");
  const BlockView view = map.blockView();
  // A mask word holds one z layer of a block (bit x + 8 y), so a coarse cell's children are the
  // bits of `layer_mask[cx, cy]` in the words of its `cells` layers: any free child, any
  // occupied child, by OR-ing (unknown when neither).
  const int per_edge = kBlockSize / cells;
  std::vector<uint64_t> layer_mask(per_edge * per_edge);
  for (int cy = 0; cy < per_edge; ++cy)
    for (int cx = 0; cx < per_edge; ++cx) {
      const uint64_t row = ((uint64_t(1) << cells) - 1) << (cx * cells);
      uint64_t mask = 0;
      for (int y = cy * cells; y < cy * cells + cells; ++y) mask |= row << (kBlockSize * y);
      layer_mask[cy * per_edge + cx] = mask;
    }
  std::vector<uint8_t> any_free(per_edge * per_edge * per_edge);
  std::vector<uint8_t> any_occupied(any_free.size());
  size_t done = 0;
  coarse.writeCells([&](CellWriter& w) {
    view.forEachIn(lo, hi, [&](const BlockKey& b, const Block&) {
      if (++done % 4096 == 0) checkQuery(control, "coarse map");
      const BlockStateMasks& m = *view.findMasks(b);
      for (int cz = 0; cz < per_edge; ++cz) {
        uint64_t free_layers = 0, occupied_layers = 0;  // the coarse layer's words OR-ed
        for (int z = cz * cells; z < cz * cells + cells; ++z) {
          free_layers |= m.free[z];
          occupied_layers |= m.occupied[z];
        }
        for (int q = 0; q < per_edge * per_edge; ++q) {
          any_free[cz * per_edge * per_edge + q] = (free_layers & layer_mask[q]) != 0;
          any_occupied[cz * per_edge * per_edge + q] = (occupied_layers & layer_mask[q]) != 0;
        }
      }
      const VoxelKey origin = voxelKeyOf(b, 0);
      for (int cz = 0; cz < per_edge; ++cz)
        for (int cy = 0; cy < per_edge; ++cy)
          for (int cx = 0; cx < per_edge; ++cx) {
            const int c = (cz * per_edge + cy) * per_edge + cx;
            if (!any_free[c] && !any_occupied[c]) continue;  // unknown: left unobserved
            const VoxelKey k{coarseOf(origin.x, shift) + cx, coarseOf(origin.y, shift) + cy,
                             coarseOf(origin.z, shift) + cz};
            w.set(k, any_free[c] ? free_cell : occupied_cell);
          }
    });
  });
  checkQuery(control, "coarse map");
  return coarse;
}

}  // namespace

Map coarseStateMap(const Map& map, int cells, const QueryControl* control) {
  return coarseOfBlocks(map, cells, BlockKey{INT32_MIN, INT32_MIN, INT32_MIN},
                        BlockKey{INT32_MAX, INT32_MAX, INT32_MAX}, control);
}

Map coarseStateMapIn(const Map& map, int cells, const Eigen::Vector3d& lo_m,
                     const Eigen::Vector3d& hi_m, double margin_m, const QueryControl* control) {
  if (!lo_m.allFinite() || !hi_m.allFinite() || (lo_m.array() > hi_m.array()).any())
    throw InvalidArgument("coarse map box must be finite with min <= max");
  if (!std::isfinite(margin_m) || margin_m < 0.0)
    throw InvalidArgument(
        fmt::format("coarse map margin must be finite and >= 0, got {}", margin_m));
  // One coarse cell more than asked: a coarse cell inside the grown box has all 26 neighbours.
  const double grow_m = margin_m + cells * map.resolution();
  const BlockKey lo = blockKeyOf(map.keyOf(lo_m - Eigen::Vector3d::Constant(grow_m)));
  const BlockKey hi = blockKeyOf(map.keyOf(hi_m + Eigen::Vector3d::Constant(grow_m)));
  return coarseOfBlocks(map, cells, lo, hi, control);
}

int coarseCellsForBeams(double resolution_m, double angle_rad, double range_m) {
  if (!(resolution_m > 0.0) || !(angle_rad > 0.0) || !(range_m > 0.0) ||
      !std::isfinite(angle_rad * range_m))
    throw InvalidArgument(fmt::format(
        "beam spacing needs a positive resolution, angle and range, got {} m, {} rad, {} m",
        resolution_m, angle_rad, range_m));
  const double spacing_cells = angle_rad * range_m / resolution_m;
  int cells = 1;
  while (cells < 8 && 2.0 * cells <= spacing_cells) cells *= 2;
  return cells;
}

}  // namespace fragg::planning
