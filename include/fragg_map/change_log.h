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

  /// Records that block `key` changed state at map revision `revision` (once per block and
  /// revision: the caller's stamp says whether it did already, BlockMap::noteMasksChanged).
  void record(uint64_t revision, const BlockKey& key);
  /// Whether the log holds every record after `revision` (none was dropped that is newer).
  [[nodiscard]] bool reaches(uint64_t revision) const { return revision >= dropped_up_to_; }
  /// The keys recorded after `revision`, in unspecified order (including blocks erased since:
  /// the caller filters), each once -- but a block erased and made again within one revision
  /// may be listed twice when the question spans that revision alone. Only meaningful when
  /// reaches(revision).
  [[nodiscard]] std::vector<BlockKey> keysAfter(uint64_t revision) const;
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
  };
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
