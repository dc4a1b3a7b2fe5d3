// ObservedMirror: the changed blocks, copied a piece per read lock.
#include "observed_mirror.h"

#include <algorithm>
#include <chrono>
#include <thread>
#include <tuple>
#include <vector>

#include "fragg_map/cell_writer.h"
#include "fragg_map/errors.h"

namespace fragg::ros {

namespace {
fragg::MapParams copyParams(const fragg::Map& source) {
  fragg::MapParams p = source.params();
  p.backend = fragg::Backend::kCpu;
  p.scans = fragg::ScanStoreParams();
  p.scans.keep = false;
  return p;
}
}  // namespace

ObservedMirror::ObservedMirror(size_t blocks_per_lock) : blocks_per_lock_(blocks_per_lock) {
  if (blocks_per_lock_ == 0)
    throw fragg::InvalidArgument("a mirror copies at least one block a lock");
}

const fragg::Map& ObservedMirror::map() const {
  static const fragg::Map empty = [] {
    fragg::MapParams p;
    p.backend = fragg::Backend::kCpu;  // no backend choice (and its log line) for an empty map
    return fragg::Map(p);
  }();
  return copy_ ? *copy_ : empty;
}

void ObservedMirror::clear() {
  copy_.reset();
  revision_ = 0;
  epoch_ = 0;
}

ObservedMirror::RefreshStats ObservedMirror::refresh(SharedMap& shared) {
  RefreshStats stats;
  std::vector<fragg::BlockKey> keys;
  uint64_t revision = 0, epoch = 0;
  // The listing reads the host's blocks (hostBlockView): a device's changes are written back
  // first, in pieces under the write lock (Map::writeBackSome). A blockView() under the
  // listing's read lock wrote back every block changed since the last refresh at once: after a
  // frontier update of ~28 s, the suspect for a 357-472 ms insertion wait on the GPU machine;
  // and a write-back makes host blocks, which no other reader's view may see happen. The listing
  // claims the revision up to which the host's blocks are complete: the map's when nothing is
  // pending under its read lock, else the one the last piece left (what insertion changed since is
  // listed next time, its stamps newer).
  bool written_back = false;  // the last piece wrote every pending change back
  uint64_t written_back_at = 0, written_back_epoch = 0;
  for (size_t piece = 0;; ++piece) {
    {
      const SharedMap::ReadGuard state = shared.read("frontier mirror listing");
      const fragg::Map& map = state->map;
      const bool pending = map.deviceChangesPending();
      const bool complete = !pending || (written_back && written_back_epoch == map.viewEpoch());
      if (complete || piece >= kMaxWriteBackPieces) {
        ++stats.locks;
        epoch = map.viewEpoch();
        stats.rebuilt = !copy_ || epoch != epoch_ || map.resolution() != copy_->resolution() ||
                        !(map.params().occupancy == copy_->params().occupancy);
        // Complete up to: the map's revision, the last piece's, or (pieces given up on while
        // insertion kept changing the map) nothing new: what was written back is listed
        // again next time.
        revision = !pending        ? map.revision()
                   : complete      ? written_back_at
                   : stats.rebuilt ? 0
                                   : revision_;
        const fragg::BlockView view = map.hostBlockView();
        if (stats.rebuilt) {
          copy_.emplace(copyParams(map));
          keys.reserve(view.size());
          view.forEach(
              [&](const fragg::BlockKey& key, const fragg::Block&) { keys.push_back(key); });
        } else if (map.revision() != revision_) {
          keys = view.changedSince(revision_, fragg::BlockChange::kAny);
        }
        break;
      }
    }
    if (piece > 0) std::this_thread::sleep_for(std::chrono::milliseconds(1));
    SharedMap::WriteGuard state = shared.write("frontier mirror write-back");
    ++stats.write_back_pieces;
    written_back = !state->map.writeBackSome(kBlocksPerWriteBack);
    written_back_at = state->map.revision();
    written_back_epoch = state->map.viewEpoch();
  }
  stats.blocks_listed = keys.size();
  // Store order: neighbouring blocks are copied together.
  std::sort(keys.begin(), keys.end(), [](const fragg::BlockKey& a, const fragg::BlockKey& b) {
    return std::tie(a.z, a.y, a.x) < std::tie(b.z, b.y, b.x);
  });
  for (size_t first = 0; first < keys.size();) {
    const size_t most = std::min(keys.size(), first + blocks_per_lock_);
    // A pause between pieces: glibc's reader-writer lock lets a reader in ahead of a waiting
    // writer, so insertion, waiting for a piece to end, takes the lock before the next piece.
    if (first > 0) std::this_thread::sleep_for(std::chrono::milliseconds(1));
    const SharedMap::ReadGuard state = shared.read("frontier mirror piece");
    const fragg::Map& map = state->map;
    ++stats.locks;
    if (map.viewEpoch() != epoch) {
      // Blocks left the view while the pieces were copied (an erase, a reset, a load): what
      // the copy holds may be gone from the map. Rebuilt at the next refresh.
      copy_.reset();
      stats.complete = false;
      return stats;
    }
    // The host's blocks as they stand (Map::hostBlockView): written back up to `revision`
    // before the listing, so every listed block is there at least as new as that; what
    // changed since is listed next time.
    const fragg::BlockView view = map.hostBlockView();
    // A piece ends at blocks_per_lock blocks or, past kPieceCheckBlocks, at kPieceBudget of
    // wall time (an H100 host copied 2,048 blocks in 12-55 ms: an insertion waited that long).
    const auto began = std::chrono::steady_clock::now();
    size_t j = first;
    copy_->writeCells([&](fragg::CellWriter& writer) {
      for (; j < most; ++j) {
        if (j > first && (j - first) % kPieceCheckBlocks == 0 &&
            std::chrono::steady_clock::now() - began > kPieceBudget)
          break;
        if (const fragg::Block* block = view.findBlock(keys[j])) writer.setBlock(keys[j], *block);
      }
    });
    first = j;
  }
  revision_ = revision;
  epoch_ = epoch;
  return stats;
}

}  // namespace fragg::ros
