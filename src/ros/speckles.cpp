// Speckles: 26-neighbourhood lookups through a BlockView (cells) or a MaskMirror (masks).
#include "fragg_map/ros/speckles.h"

namespace fragg::ros {
namespace {

/// Whether cell `v` is occupied: from its cell (a map's view) or its block's masks (a mirror).
bool occupiedAt(const fragg::Map& map, const fragg::BlockView& blocks, const fragg::VoxelKey& v) {
  const fragg::Cell* c = blocks.findCell(v);
  return c && map.state(*c) == fragg::CellState::kOccupied;
}
bool occupiedAt(const fragg::Map& /*map*/, const MaskMirror& blocks, const fragg::VoxelKey& v) {
  const fragg::BlockStateMasks* m = blocks.findMasks(fragg::blockKeyOf(v));
  return m && m->state(fragg::cellIndexOf(v)) == fragg::CellState::kOccupied;
}

template <class View>
bool speckleIn(const fragg::Map& map, const View& blocks, const fragg::VoxelKey& v) {
  for (int dz = -1; dz <= 1; ++dz)
    for (int dy = -1; dy <= 1; ++dy)
      for (int dx = -1; dx <= 1; ++dx) {
        if (dx == 0 && dy == 0 && dz == 0) continue;
        if (occupiedAt(map, blocks, {v.x + dx, v.y + dy, v.z + dz})) return false;
      }
  return true;
}

template <class View>
CellMask specklesOut(const fragg::Map& map, const View& blocks, const fragg::BlockKey& key,
                     CellMask cells) {
  for (int c = 0; c < fragg::kCellsPerBlock; ++c)
    if (cells.test(c) && speckleIn(map, blocks, fragg::voxelKeyOf(key, c))) cells.reset(c);
  return cells;
}

}  // namespace

bool isSpeckle(const fragg::Map& map, const fragg::BlockView& blocks, const fragg::VoxelKey& v) {
  return speckleIn(map, blocks, v);
}

CellMask withoutSpeckles(const fragg::Map& map, const fragg::BlockView& blocks,
                         const fragg::BlockKey& key, CellMask cells) {
  return specklesOut(map, blocks, key, cells);
}

bool isSpeckle(const fragg::Map& map, const MaskMirror& blocks, const fragg::VoxelKey& v) {
  return speckleIn(map, blocks, v);
}

CellMask withoutSpeckles(const fragg::Map& map, const MaskMirror& blocks,
                         const fragg::BlockKey& key, CellMask cells) {
  return specklesOut(map, blocks, key, cells);
}

}  // namespace fragg::ros
