#include "fragg_map/change_log.h"

#include <algorithm>
#include <unordered_set>

namespace fragg {

void BlockChangeLog::record(uint64_t revision, const BlockKey& key) {
  if (revision <= dropped_up_to_) return;  // older than what the log answers for anyway
  if (records_.size() >= capacity_) dropOldest();
  records_.push_back({revision, key});
}

void BlockChangeLog::dropOldest() {
  // Records arrive nearly in revision order (a device write-back may bring older ones).
  std::stable_sort(records_.begin(), records_.end(),
                   [](const Record& a, const Record& b) { return a.revision < b.revision; });
  const size_t half = records_.size() / 2;
  if (half == 0) return;
  uint64_t cut = records_[half - 1].revision;
  // Whole revisions go: the records of the cut revision after the half go too.
  size_t end = half;
  while (end < records_.size() && records_[end].revision == cut) ++end;
  records_.erase(records_.begin(), records_.begin() + static_cast<std::ptrdiff_t>(end));
  dropped_up_to_ = std::max(dropped_up_to_, cut);
}

std::vector<BlockKey> BlockChangeLog::keysAfter(uint64_t revision) const {
  std::vector<BlockKey> out;
  std::unordered_set<BlockKey, BlockKeyHash> seen;
  for (const Record& r : records_)
    if (r.revision > revision && seen.insert(r.key).second) out.push_back(r.key);
  return out;
}

}  // namespace fragg
