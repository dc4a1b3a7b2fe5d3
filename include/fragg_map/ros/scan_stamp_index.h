// Which kept scan a stamp names: the map server's stamp -> ScanId index for ~correct_poses and
// corrected_path. Filled as scans are inserted (with the cloud's frame), rebuilt from a loaded
// map's scan store (frames unknown there: ScanStore keeps none), cleared on reset.
#pragma once

#include <cstdint>
#include <map>
#include <string>

#include "fragg_map/scan_store.h"

namespace fragg::ros {

class ScanStampIndex {
 public:
  struct Entry {
    fragg::ScanId id = 0;
    std::string sensor_frame;  ///< the cloud's frame; empty for scans loaded from a file
  };

  /// Adds a kept scan. A stamp that is already indexed now names the newer scan.
  void add(int64_t stamp_ns, fragg::ScanId id, const std::string& sensor_frame);
  /// Every scan of `store`, by its stamp (sensor frames unknown).
  void rebuild(const fragg::ScanStore& store);
  void clear() { by_stamp_.clear(); }
  size_t size() const { return by_stamp_.size(); }

  /// The scan whose stamp is nearest to `stamp_ns`, when it is within `tolerance_ns`
  /// (inclusive); nullptr otherwise. On a tie the earlier stamp wins.
  const Entry* find(int64_t stamp_ns, int64_t tolerance_ns) const;

 private:
  std::map<int64_t, Entry> by_stamp_;
};

}  // namespace fragg::ros
