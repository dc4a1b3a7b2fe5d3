#include "fragg_map/change_log.h"

#include <algorithm>

#include "fragg_map/block_key_table.h"

namespace fragg {

void BlockChangeLog::record(uint64_t revision, const BlockKey& key, uint32_t slot) {
  if (revision <= dropped_up_to_) return;  // older than what the log answers for anyway
  if (records_.size() >= capacity_) dropOldest();
  if (sorted_up_to_ == records_.size() &&
      (records_.empty() || records_.back().revision <= revision))
    ++sorted_up_to_;  // still in revision order
  records_.push_back({revision, key, slot});
}

void BlockChangeLog::dropOldest() {
  // Records arrive nearly in revision order (a device write-back may bring older ones): the
  // prefix still in order is kept, the rest sorted and merged into it (both stable: the order
  // a whole stable sort gives).
  const auto by_revision = [](const Record& a, const Record& b) { return a.revision < b.revision; };
  const auto mid = records_.begin() + static_cast<std::ptrdiff_t>(sorted_up_to_);
  std::stable_sort(mid, records_.end(), by_revision);
  std::inplace_merge(records_.begin(), mid, records_.end(), by_revision);
  const size_t half = records_.size() / 2;
  if (half == 0) return;
  uint64_t cut = records_[half - 1].revision;
  // Whole revisions go: the records of the cut revision after the half go too.
  size_t end = half;
  while (end < records_.size() && records_[end].revision == cut) ++end;
  records_.erase(records_.begin(), records_.begin() + static_cast<std::ptrdiff_t>(end));
  dropped_up_to_ = std::max(dropped_up_to_, cut);
  sorted_up_to_ = records_.size();
}

size_t BlockChangeLog::firstSortedAfter(uint64_t revision) const {
  // The records in revision order are searched, the rest (a device's write-back may bring
  // older revisions) scanned: a question about the last scan reads that scan's records only.
  const auto sorted_end = records_.begin() + static_cast<std::ptrdiff_t>(sorted_up_to_);
  const auto first =
      std::upper_bound(records_.begin(), sorted_end, revision,
                       [](uint64_t r, const Record& rec) { return r < rec.revision; });
  return static_cast<size_t>(first - records_.begin());
}

std::vector<BlockKey> BlockChangeLog::keysAfter(uint64_t revision) const {
  const auto first = records_.begin() + static_cast<std::ptrdiff_t>(firstSortedAfter(revision));
  std::vector<BlockKey> out;
  // One revision in order (a question about the last scan): each block is recorded once.
  if (sorted_up_to_ == records_.size() &&
      (first == records_.end() || first->revision == records_.back().revision)) {
    out.reserve(static_cast<size_t>(records_.end() - first));
    for (auto it = first; it != records_.end(); ++it) out.push_back(it->key);
    return out;
  }
  BlockKeyTable seen;
  seen.reserve(static_cast<size_t>(records_.end() - first));
  for (auto it = first; it != records_.end(); ++it) {
    if (it->revision <= revision || seen.find(it->key) != BlockKeyTable::kNone) continue;
    seen.insert(it->key, 0);
    out.push_back(it->key);
  }
  return out;
}

}  // namespace fragg
