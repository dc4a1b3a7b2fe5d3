// The map and its stamp -> scan index behind one reader/writer lock (fragg::Locked), shared by
// the insertion thread, publishers, services and corrected_path. The index changes only with
// the map, under the write lock: insertion adds, ~load_map rebuilds, ~reset clears.
//
// Who takes which side: publishers, ~save_map (a .fgm: for the copy only, Map::image, as the
// autosave; a .bt: the whole export), ~get_stats, ~check_collision and ~truncate with keep
// read; insertion (one scan per lock), ~clear_bbox, ~reset, ~load_map, the pose corrections,
// ~truncate (removing) and ~merge write.
#pragma once

#include <utility>

#include "fragg_map/map.h"
#include "fragg_map/map_lock.h"
#include "fragg_map/planning/beam_spacing.h"
#include "fragg_map/ros/scan_stamp_index.h"

namespace fragg::ros {

struct MapState {
  explicit MapState(fragg::Map m) : map(std::move(m)) {}
  fragg::Map map;
  ScanStampIndex stamps;  ///< kept scans by stamp (empty when the map keeps none)
  /// The LiDAR's beam spacing from the first clouds (frontiers/coarse_cells 0 sizes the
  /// frontier grid from it); kept across ~reset and ~load_map (the sensor stays the same).
  planning::BeamSpacingTracker beams;
};

using SharedMap = fragg::Locked<MapState>;

}  // namespace fragg::ros
