// octomap_server's filter_speckles: an occupied cell none of whose 26 neighbours is occupied
// (unknown and free neighbours alike) is a speckle, left out of the published views
// (markers, occupied cloud, projected map); the map itself keeps it.
#pragma once

#include "fragg_map/block_view.h"
#include "fragg_map/key.h"
#include "fragg_map/map.h"
#include "fragg_map/ros/block_markers.h"
#include "fragg_map/ros/mask_mirror.h"

namespace fragg::ros {

/// Whether the cell `v` has no occupied neighbour among its 26. `blocks` is `map.blockView()`
/// (taken once: lookups through it need no lock, so callers may run in parallel).
bool isSpeckle(const fragg::Map& map, const fragg::BlockView& blocks, const fragg::VoxelKey& v);

/// `cells` (cells of block `key`) without the speckles.
CellMask withoutSpeckles(const fragg::Map& map, const fragg::BlockView& blocks,
                         const fragg::BlockKey& key, CellMask cells);

/// The same over a mask mirror: the neighbours' occupancy from their state masks (as of the
/// mirror's last sync). `map` is unused (the signature matches the view's).
bool isSpeckle(const fragg::Map& map, const MaskMirror& blocks, const fragg::VoxelKey& v);
/// `cells` without the speckles, over a mask mirror.
CellMask withoutSpeckles(const fragg::Map& map, const MaskMirror& blocks,
                         const fragg::BlockKey& key, CellMask cells);

}  // namespace fragg::ros
