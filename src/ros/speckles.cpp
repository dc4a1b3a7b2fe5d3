// Speckles: 26-neighbourhood lookups through a BlockView.
#include "fragg_map/ros/speckles.h"

namespace fragg::ros {

bool isSpeckle(const fragg::Map& map, const fragg::BlockView& blocks, const fragg::VoxelKey& v) {
  for (int dz = -1; dz <= 1; ++dz)
    for (int dy = -1; dy <= 1; ++dy)
      for (int dx = -1; dx <= 1; ++dx) {
        if (dx == 0 && dy == 0 && dz == 0) continue;
        const fragg::Cell* c = blocks.findCell({v.x + dx, v.y + dy, v.z + dz});
        if (c && map.state(*c) == fragg::CellState::kOccupied) return false;
      }
  return true;
}

CellMask withoutSpeckles(const fragg::Map& map, const fragg::BlockView& blocks,
                         const fragg::BlockKey& key, CellMask cells) {
  for (int c = 0; c < fragg::kCellsPerBlock; ++c)
    if (cells.test(c) && isSpeckle(map, blocks, fragg::voxelKeyOf(key, c))) cells.reset(c);
  return cells;
}

bool isSpeckle(const fragg::Map& /*map*/, const MaskMirror& blocks, const fragg::VoxelKey& v) {
  for (int dz = -1; dz <= 1; ++dz)
    for (int dy = -1; dy <= 1; ++dy)
      for (int dx = -1; dx <= 1; ++dx) {
        if (dx == 0 && dy == 0 && dz == 0) continue;
        const fragg::VoxelKey n{v.x + dx, v.y + dy, v.z + dz};
        const fragg::BlockStateMasks* m = blocks.findMasks(fragg::blockKeyOf(n));
        if (m && m->state(fragg::cellIndexOf(n)) == fragg::CellState::kOccupied) return false;
      }
  return true;
}

CellMask withoutSpeckles(const fragg::Map& map, const MaskMirror& blocks,
                         const fragg::BlockKey& key, CellMask cells) {
  for (int c = 0; c < fragg::kCellsPerBlock; ++c)
    if (cells.test(c) && isSpeckle(map, blocks, fragg::voxelKeyOf(key, c))) cells.reset(c);
  return cells;
}

}  // namespace fragg::ros
