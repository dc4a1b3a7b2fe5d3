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

ObservedMirror::RefreshStats ObservedMirror::refresh(const SharedMap& shared) {
  RefreshStats stats;
  std::vector<fragg::BlockKey> keys;
  uint64_t revision = 0, epoch = 0;
  {
    const SharedMap::ReadGuard state = shared.read("frontier mirror listing");
    const fragg::Map& map = state->map;
    ++stats.locks;
    revision = map.revision();
    epoch = map.viewEpoch();
    stats.rebuilt = !copy_ || epoch != epoch_ || map.resolution() != copy_->resolution() ||
                    !(map.params().occupancy == copy_->params().occupancy);
    if (stats.rebuilt) {
      copy_.emplace(copyParams(map));
      const fragg::BlockView view = map.blockView();
      keys.reserve(view.size());
      view.forEach([&](const fragg::BlockKey& key, const fragg::Block&) { keys.push_back(key); });
    } else if (revision != revision_) {
      keys = map.changedBlocksSince(revision_, fragg::BlockChange::kAny);
    }
  }
  stats.blocks_listed = keys.size();
  // Store order: neighbouring blocks are copied together.
  std::sort(keys.begin(), keys.end(), [](const fragg::BlockKey& a, const fragg::BlockKey& b) {
    return std::tie(a.z, a.y, a.x) < std::tie(b.z, b.y, b.x);
  });
  for (size_t first = 0; first < keys.size(); first += blocks_per_lock_) {
    const size_t last = std::min(keys.size(), first + blocks_per_lock_);
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
    // The host's blocks as they stand (Map::hostBlockView): the listing's blockView() wrote
    // a device's changes back, so every listed block is there at least as new as `revision`;
    // what changed since is listed next time. A write-back per piece (blockView) would cost
    // a CUDA map's insertion a write-back of its last cloud at every piece.
    const fragg::BlockView view = map.hostBlockView();
    copy_->writeCells([&](fragg::CellWriter& writer) {
      for (size_t j = first; j < last; ++j)
        if (const fragg::Block* block = view.findBlock(keys[j])) writer.setBlock(keys[j], *block);
    });
  }
  revision_ = revision;
  epoch_ = epoch;
  return stats;
}

}  // namespace fragg::ros
