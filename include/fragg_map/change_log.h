// Which blocks changed state, by map revision (DESIGN §12, issue 34 item 2): the writers of the
// state masks (the backends' updates, their write-back, the named edits) record a block's key
// when its masks change, so readers ask "which blocks changed state since revision r" without
// walking the map. Bounded: the oldest records go first, and a question reaching back before
// them gets no answer (the caller walks the blocks' stamps instead).
#pragma once

#include <cstddef>
#include <cstdint>
#include <vector>

#include "fragg_map/key.h"

namespace fragg {

class BlockChangeLog {
 public:
  /// Records kept at most (24 bytes each); the older half goes when it is full.
  static constexpr size_t kDefaultCapacity = size_t{1} << 20;

  explicit BlockChangeLog(size_t capacity = kDefaultCapacity) : capacity_(capacity) {}

  /// A record's slot when the writer did not say (a log on its own).
  static constexpr uint32_t kNoSlot = 0xffffffffu;

  /// Records that block `key` changed state at map revision `revision` (once per block and
  /// revision: the caller's stamp says whether it did already, BlockMap::noteMasksChanged).
  /// `slot`: where the block was then (BlockMap's index; a hint: the slot may hold another
  /// block by the time the record is read).
  void record(uint64_t revision, const BlockKey& key, uint32_t slot = kNoSlot);
  /// Whether the log holds every record after `revision` (none was dropped that is newer).
  [[nodiscard]] bool reaches(uint64_t revision) const { return revision >= dropped_up_to_; }
  /// The keys recorded after `revision`, in unspecified order (including blocks erased since:
  /// the caller filters), each once -- but a block erased and made again within one revision
  /// may be listed twice when the question spans that revision alone. Only meaningful when
  /// reaches(revision).
  [[nodiscard]] std::vector<BlockKey> keysAfter(uint64_t revision) const;
  /// Calls fn(key, slot) for every record after `revision` (`slot` as recorded), in the log's
  /// order, a block once per revision it was recorded in. Only meaningful when reaches(revision).
  template <class Fn>
  void forEachAfter(uint64_t revision, Fn&& fn) const {
    const size_t first = firstSortedAfter(revision);
    for (size_t i = first; i < records_.size(); ++i) {
      const Record& r = records_[i];
      // Past the ordered prefix (a write-back's older revisions) each record is checked.
      if (i >= sorted_up_to_ && r.revision <= revision) continue;
      fn(r.key, r.slot);
    }
  }
  /// Forgets every record (the map's blocks are gone); what it answers stays complete.
  void clear() {
    records_.clear();
    sorted_up_to_ = 0;
  }
  [[nodiscard]] size_t size() const { return records_.size(); }
  [[nodiscard]] size_t bytes() const { return records_.capacity() * sizeof(Record); }

 private:
  struct Record {
    uint64_t revision;
    BlockKey key;
    uint32_t slot;  ///< in the padding of the 24 bytes revision and key take anyway
  };
  static_assert(sizeof(Record) == 24, "a record's slot fits its padding");
  /// The first record of the ordered prefix after `revision` (the prefix's end when none).
  [[nodiscard]] size_t firstSortedAfter(uint64_t revision) const;
  /// Drops the older half of the records (by revision).
  void dropOldest();

  size_t capacity_;
  std::vector<Record> records_;
  /// Records of revisions <= this were dropped.
  uint64_t dropped_up_to_ = 0;
  /// records_[0, sorted_up_to_) are in revision order (a binary search finds a question's
  /// first record there).
  size_t sorted_up_to_ = 0;
};

}  // namespace fragg
