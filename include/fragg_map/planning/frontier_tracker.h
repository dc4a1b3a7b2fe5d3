// Incremental frontier cells: after each scan the map's changed-block list (Map::
// masksChangedSince: the blocks whose state masks changed, with their masks; on a CUDA map
// compacted on the device) updates the tracker's copy of the masks without reading a cell; a
// changed block is examined again (bit-parallel, frontier_masks.h), and of its 26 neighbours
// those whose shared face, edge or corner saw an unknown cell come or go; the set always
// equals findFrontierCells() on the same map and filter. A map whose blocks left or joined its
// view since the last update (clearBox, truncate, reset, paging: Map::viewEpoch), or another
// map, is recomputed in full. On a paged map only resident blocks are seen: page the region of
// interest in first (Map::ensureResident). By default (useDevice(true)), on a CUDA map (no obstacle
// distance filter) the whole update runs on the map's device: the tracker keeps what it saw per
// slot of the pool there, compares every slot of the map's device layer view with it, examines the
// neighbourhoods that changed there, and brings back the count only; cells() and
// forEachBlock() download the blocks with frontier cells when asked.
#pragma once

#include <cstdint>
#include <functional>
#include <memory>
#include <vector>

#include "fragg_map/planning/frontier_cells.h"
#include "fragg_map/planning/query_control.h"
#include "fragg_map/state_masks.h"

namespace fragg::planning {

struct FrontierUpdateStats {
  bool full = false;             ///< recomputed every block
  uint64_t blocks_changed = 0;   ///< changed blocks whose cell states were read again
  uint64_t blocks_examined = 0;  ///< blocks whose frontier cells were recomputed
  uint64_t cells = 0;            ///< frontier cells after the update
  /// The update ran on the map's device (a CUDA map): masks compared and blocks examined
  /// there, the host map not written back; blocks_changed counts the pool slots whose masks
  /// changed (or whose block left).
  bool states_on_device = false;
  double seconds = 0.0;
  /// Where the time went: the changed-block list with masks (on the device or the host),
  /// comparing them and listing the neighbourhoods to examine, and examining them (the
  /// bit-parallel test).
  double states_seconds = 0.0, compare_seconds = 0.0, examine_seconds = 0.0;
};

/// What an update reads from the map, copied under the map's read lock (FrontierTracker::
/// collect) so that the update itself (FrontierTracker::apply) runs without the lock: the
/// changed-block list with masks since the tracker's revision, or, when the update must be
/// full, every block's masks.
struct FrontierMapChanges {
  bool full = false;                   ///< keys/masks are every block (else the blocks changed)
  uint64_t base_revision = 0;          ///< the tracker's revision at collect()
  bool base_valid = false;             ///< whether the tracker held a set at collect()
  uint64_t revision = 0;               ///< the map's revision at collect()
  uint64_t view_epoch = 0;             ///< the map's Map::viewEpoch() at collect()
  double resolution_m = 0.0;           ///< the map's resolution
  std::vector<BlockKey> keys;          ///< the blocks
  std::vector<BlockStateMasks> masks;  ///< their state masks, in the order of keys
};

class FrontierTracker {
 public:
  /// Throws InvalidArgument for a bad filter or negative thread count.
  explicit FrontierTracker(const FrontierFilter& filter = {}, int threads = 0);
  ~FrontierTracker();
  FrontierTracker(FrontierTracker&&) noexcept;
  FrontierTracker& operator=(FrontierTracker&&) noexcept;

  /// Brings the set up to date with `map` (hold its read lock). With a `control` whose
  /// deadline passes or that is cancelled, throws QueryStopped and forgets the set (the next
  /// update is a full one).
  FrontierUpdateStats update(const Map& map, const QueryControl* control = nullptr);
  /// What update(map) would read, copied (hold the map's read lock; the tracker is not
  /// changed): the changed-block list with masks (the change log: no cell read), or every
  /// block's masks when the update must be full. Throws InvalidArgument for a filter with
  /// min_obstacle_distance_m > 0 (it reads cells: use update()).
  [[nodiscard]] FrontierMapChanges collect(const Map& map) const;
  /// The update from what collect() copied, without the map: the same set as update(map) at
  /// that revision. Pairs with the collect() just before it (InvalidArgument when the tracker
  /// changed in between: nothing changes). `control` as update()'s.
  FrontierUpdateStats apply(const FrontierMapChanges& changes,
                            const QueryControl* control = nullptr);
  /// Forgets everything: the next update is a full one.
  void reset();
  /// Whether update() on a CUDA map runs on the map's device (frontier_kernels.cu; on by
  /// default; test/gpu/frontier_gpu_test.cpp checks it against the CPU). Off: the host update,
  /// fed by the changed-block list compacted on the device. A change takes effect with a full
  /// update.
  void useDevice(bool on);

  /// The frontier cells, sorted by frontierOrder.
  std::vector<VoxelKey> cells() const;
  /// Calls fn(block, bits) for every block with frontier cells, in blockOrder; bit i of
  /// bits[i / 64] is the cell with index i (cellIndexOf). Cheaper than cells() for callers that
  /// work per block (tens of millions of frontier cells on a LiDAR map at 5 cm).
  void forEachBlock(const std::function<void(const BlockKey&, const uint64_t* bits)>& fn) const;
  uint64_t size() const;
  /// The map revision the set belongs to.
  uint64_t revision() const;
  const FrontierFilter& filter() const;

 private:
  /// update() once its control is installed.
  FrontierUpdateStats updateChecked(const Map& map);
  struct State;
  std::unique_ptr<State> state_;
};

}  // namespace fragg::planning
