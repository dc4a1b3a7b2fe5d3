// A copy of the shared map's observed cells kept up to date in pieces, for long readers that
// run again and again (the frontier topics' clusters and viewpoints, at frontiers/rate_hz):
// observedCopy (map_copy.h) copies the whole map under one read lock, which on a big map held
// insertion back for seconds at every tick (W1 on the GPU machine: a 3.4 s stall, 29 clouds
// dropped). The mirror copies only the blocks changed since its last refresh, a bounded number
// per read lock (whole blocks, CellWriter::setBlock), the lock released for a millisecond
// between pieces.
#pragma once

#include <chrono>
#include <cstddef>
#include <cstdint>
#include <optional>

#include "fragg_map/map.h"
#include "shared_map.h"

namespace fragg::ros {

class ObservedMirror {
 public:
  /// What one refresh did.
  struct RefreshStats {
    bool rebuilt = false;          ///< every block copied (the first refresh, a new view epoch)
    size_t blocks_listed = 0;      ///< blocks changed since the last refresh (all when rebuilt)
    size_t locks = 0;              ///< read locks taken (one for the listing, one a piece)
    size_t write_back_pieces = 0;  ///< write locks taken to write a device's changes back
    bool complete = true;          ///< false: the map's view changed mid-way; the next one rebuilds
  };

  /// Blocks a device writes back under one write lock (Map::writeBackSome; ~2.3 KB each). An
  /// H100 host wrote back 1.4-2.2 us a block: 8,192 a piece held insertion back 12-20 ms.
  static constexpr size_t kBlocksPerWriteBack = 2048;
  /// Write-back pieces a refresh takes at most before it lists what the host holds (a map
  /// that a device changes faster than pieces write back: what is left comes next time).
  static constexpr size_t kMaxWriteBackPieces = 2048;
  /// A copied piece ends at this much wall time (checked every kPieceCheckBlocks blocks), or
  /// at blocks_per_lock blocks, whichever comes first.
  static constexpr std::chrono::microseconds kPieceBudget{2000};
  static constexpr size_t kPieceCheckBlocks = 8;

  /// `blocks_per_lock`: blocks copied under one read lock at most (> 0; 2 KiB each).
  explicit ObservedMirror(size_t blocks_per_lock = 2048);

  /// Brings the copy up to `shared`'s map: every observed cell as the map holds it at the
  /// revision read at the start, or newer (blocks that change while the pieces are copied are
  /// copied again by the next refresh). A change of the map's view epoch (blocks erased, paged,
  /// a reset or load) rebuilds the copy from every block. Takes the map's read lock, for one
  /// piece at a time; on a CUDA map whose device holds changes not written back, first the
  /// write lock for each piece of that write-back (kBlocksPerWriteBack blocks).
  RefreshStats refresh(SharedMap& shared);

  /// Drops the copy and its memory (as much as the map's observed blocks); the next refresh
  /// rebuilds it.
  void clear();

  /// The copy (a CPU map of the source's resolution and occupancy model, no kept scans); empty
  /// before the first refresh. Read it between refreshes, from the thread that refreshes.
  [[nodiscard]] const fragg::Map& map() const;
  /// The source's revision the copy has reached (every change up to it is in the copy).
  [[nodiscard]] uint64_t revision() const { return revision_; }

 private:
  size_t blocks_per_lock_;
  std::optional<fragg::Map> copy_;
  uint64_t revision_ = 0;
  uint64_t epoch_ = 0;
};

}  // namespace fragg::ros
