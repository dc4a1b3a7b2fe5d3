// The stamp -> ScanId index: nearest stamp within a tolerance.
#include "fragg_map/ros/scan_stamp_index.h"

#include <iterator>

namespace fragg::ros {

void ScanStampIndex::add(int64_t stamp_ns, fragg::ScanId id, const std::string& sensor_frame) {
  by_stamp_[stamp_ns] = Entry{id, sensor_frame};
}

void ScanStampIndex::rebuild(const fragg::ScanStore& store) {
  by_stamp_.clear();
  for (fragg::ScanId id : store.ids()) {
    const fragg::ScanRecord& r = store.record(id);
    add(r.stamp_ns, id, r.sensor_frame);
  }
}

const ScanStampIndex::Entry* ScanStampIndex::find(int64_t stamp_ns, int64_t tolerance_ns) const {
  if (tolerance_ns < 0 || by_stamp_.empty()) return nullptr;
  // The first stamp >= stamp_ns and the one before it are the only candidates.
  auto after = by_stamp_.lower_bound(stamp_ns);
  const Entry* best = nullptr;
  uint64_t best_gap = 0;
  auto consider = [&](std::map<int64_t, Entry>::const_iterator it) {
    // Unsigned difference: stamps far apart must not overflow int64.
    const uint64_t gap = it->first >= stamp_ns
                             ? static_cast<uint64_t>(it->first) - static_cast<uint64_t>(stamp_ns)
                             : static_cast<uint64_t>(stamp_ns) - static_cast<uint64_t>(it->first);
    if (gap <= static_cast<uint64_t>(tolerance_ns) && (!best || gap < best_gap)) {
      best = &it->second;
      best_gap = gap;
    }
  };
  if (after != by_stamp_.begin()) consider(std::prev(after));
  if (after != by_stamp_.end()) consider(after);
  return best;
}

}  // namespace fragg::ros
