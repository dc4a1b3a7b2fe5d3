// The map, its stamp -> scan index and the lock every thread takes to use them (insertion
// worker, publishers, services, corrected_path). The index changes only with the map, under
// the same lock: insertion adds, ~load_map rebuilds, ~reset clears.
#pragma once

#include <mutex>
#include <utility>

#include "fragg_map/map.h"
#include "fragg_map/ros/scan_stamp_index.h"

namespace fragg::ros {

struct SharedMap {
  explicit SharedMap(fragg::Map m) : map(std::move(m)) {}
  std::mutex mutex;
  fragg::Map map;
  ScanStampIndex stamps;  ///< kept scans by stamp (empty when the map keeps none)
};

}  // namespace fragg::ros
