// The backend interface (DESIGN §11): a backend integrates or removes a prepared scan, and
// keeps a block cache, the memory it works in (the CPU backend works on the host map itself;
// the CUDA backend keeps a device copy of the blocks it needs, written back on demand).
// Out-of-core paging sits under the cache. Readers reach the layers through views
// (BlockView on the host, DeviceLayerView on a device), never through per-product calls.
#pragma once

#include <Eigen/Geometry>
#include <cstdint>
#include <functional>
#include <memory>
#include <utility>
#include <vector>

#include "fragg_map/block_map.h"
#include "fragg_map/culling.h"
#include "fragg_map/device_layer_view.h"
#include "fragg_map/device_scratch.h"
#include "fragg_map/frustum.h"
#include "fragg_map/insert_stats.h"
#include "fragg_map/internal/auto_sensor_stats.h"
#include "fragg_map/map_params.h"
#include "fragg_map/occupancy.h"
#include "fragg_map/point_cloud.h"
#include "fragg_map/sensor_model.h"

namespace fragg {

/// One scan as the map hands it to a backend (the sensor model is resolved, not auto).
struct ScanInput {
  const PointCloud& cloud;  ///< sensor frame
  const Eigen::Isometry3d& T_map_sensor;
  const SensorModel& model;
  const Frustum& frustum;
  bool explicit_model;
  const CullContext& cull;  ///< coherence context of this scan
  /// The backend's autoSensorStats() was called with this very cloud just before (nothing in
  /// between), or the update just before staged it (UpdateSettings::stage_next): what the
  /// backend kept of the cloud (the CUDA backend: its upload) may be used.
  bool cloud_staged = false;
};

/// What a scan's updates do to the map.
enum class ScanUpdate {
  kIntegrate,  ///< apply the updates (each cell at most once, hit wins)
  /// Loop closure: walk the same rays and undo the scan's updates (OccupancyModel::unapply);
  /// blocks that do not exist are not created.
  kRemove,
};

/// Where a backend's blocks live while it works on them. The host map (BlockMap) is the map;
/// a cache may hold newer copies (write-back) until sync(). Every call takes the host map.
class BlockCache {
 public:
  virtual ~BlockCache() = default;
  /// Brings the host blocks with these keys into the backend's memory (keys without a host
  /// block are skipped). Throws CudaOutOfMemory when they cannot all be held at once.
  virtual void ensureResident(const std::vector<BlockKey>& keys, BlockMap& blocks) = 0;
  /// The same for every host block whose key lies in [lo, hi] (inclusive).
  virtual void ensureResident(const BlockKey& lo, const BlockKey& hi, BlockMap& blocks) = 0;
  /// Writes the cache's changes back into `blocks`: after it the host map is complete. Cheap
  /// when nothing changed since the last call.
  virtual void sync(BlockMap& blocks) = 0;
  /// Writes back at most `max_blocks` (>= 1) of the cache's changed blocks, lowest slots
  /// first; true when changed blocks are left (more calls, or sync(), write them). For a
  /// writer that brings the host map up to date in pieces, each under a short lock.
  virtual bool syncSome(BlockMap& blocks, size_t max_blocks) = 0;
  /// Whether sync() has anything to write back.
  virtual bool needsSync() const = 0;
  /// Blocks the cache holds that the host map lacks (created in the backend's memory since
  /// the last sync(), which gives them host blocks): paging counts them against its budget
  /// without a sync after every scan.
  virtual size_t blocksNotInHostMap() const = 0;
  /// Before the host blocks in [lo, hi] are changed directly (clear box, sub-map edits):
  /// writes back, then forgets every cached copy of a block there.
  virtual void invalidate(const BlockKey& lo, const BlockKey& hi, BlockMap& blocks) = 0;
  /// invalidate() over the whole map (load, reset, import).
  virtual void invalidateAll(BlockMap& blocks) = 0;
  /// Paging: the host blocks `host_blocks` are about to be erased (paged out): their cached
  /// copies go, written back first when changed; the rest of the cache stays.
  virtual void forget(const std::vector<BlockIndex>& host_blocks, BlockMap& blocks) = 0;
  /// Paging: host blocks were created (paged in) where the cache holds no copy of a block.
  virtual void added(const std::vector<BlockIndex>& host_blocks, const BlockMap& blocks) = 0;
  /// Memory the cache holds outside the host map.
  virtual size_t deviceBytes() const = 0;
};

/// The CPU backend's cache: its working memory is the host map, so there is nothing to do.
class HostBlockCache final : public BlockCache {
 public:
  void ensureResident(const std::vector<BlockKey>&, BlockMap&) override {}
  void ensureResident(const BlockKey&, const BlockKey&, BlockMap&) override {}
  void sync(BlockMap&) override {}
  bool syncSome(BlockMap&, size_t) override { return false; }
  bool needsSync() const override { return false; }
  size_t blocksNotInHostMap() const override { return 0; }
  void invalidate(const BlockKey&, const BlockKey&, BlockMap&) override {}
  void invalidateAll(BlockMap&) override {}
  void forget(const std::vector<BlockIndex>&, BlockMap&) override {}
  void added(const std::vector<BlockIndex>&, const BlockMap&) override {}
  size_t deviceBytes() const override { return 0; }
};

/// Out-of-core paging, for a backend that asks for the blocks its rays reach
/// (MapBackend::pagesInMarkedBlocks): the blocks of `keys` that are paged out are read back
/// into the host map; blocks of other regions may be paged out to make room for `keys` (the
/// budget is a hard limit), so block indices found before the call are stale. Throws IoError
/// (or InvalidArgument when `keys` alone exceed the budget) with the map's cells as before.
using PageInKeys = std::function<void(const std::vector<BlockKey>& keys)>;
/// Paging: whether a block the host map lacks is paged out with every cell at the lower clamp
/// (BlockMeta::freeSaturated when it left), so that the rays' misses may skip it as they skip
/// such a resident block. Called from every ray-casting thread at once.
using PagedOutSaturated = std::function<bool(const BlockKey& key)>;

/// Out-of-core paging for a backend that keeps blocks of its own (MapBackend::reportsReachedBlocks,
/// the CUDA backend): the map pages nothing in before the scan; the backend's rays report the
/// blocks they reach that the host map lacks, and the blocks they create count against the
/// budget as they are made.
struct DevicePaging {
  /// The regions with a paged-out block that meet [lo, hi], as block-key boxes (a region's
  /// first and last block): no block may be created there before the region is paged in.
  std::function<std::vector<std::pair<BlockKey, BlockKey>>(const BlockKey& lo, const BlockKey& hi)>
      paged_out_regions;
  /// Blocks that may still be created (on the device, or read back) before the budget is
  /// full, beside the host map and the blocks the backend holds that the host map lacks.
  std::function<size_t()> room;
  /// Reads back the paged-out blocks of the regions of `reached` (blocks the rays reached),
  /// after making room under the budget for them and `new_blocks` more: regions other than
  /// those of `reached` and `pinned` (blocks the scan in progress holds) are paged out, their
  /// cached copies forgotten (BlockCache::forget). Host block indices found before are stale.
  /// Throws InvalidArgument (the same message as PageInKeys) when they cannot fit, IoError when
  /// the store fails; nothing of the scan is applied then.
  std::function<void(const std::vector<BlockKey>& reached, const std::vector<BlockKey>& pinned,
                     size_t new_blocks)>
      make_room;
};

/// The map's settings a scan update needs.
struct UpdateSettings {
  const MapParams& params;  ///< ray cast mode and no-return setting are the scan's own
  const OccupancyModel& model;
  uint64_t revision;  ///< stamped on the blocks the scan changes
  /// Paging: called with every block the scan's rays mark when the host map lacks one, before
  /// any is created (null: no paging, or the map paged in the scan's whole box first).
  const PageInKeys* page_in = nullptr;
  /// With page_in: see PagedOutSaturated (null: no such block is known).
  const PagedOutSaturated* paged_out_saturated = nullptr;
  /// With page_in and MapParams::dynamic: page_in for `keys` and the 26 blocks around each
  /// that exist, resident or paged out (the void rules read the map around the cells a scan
  /// touches): called with the hits' blocks before they are classified, and in place of
  /// page_in with the marked blocks after the rays, before the rules read them.
  const PageInKeys* page_in_around = nullptr;
  /// Paging on a backend that reports the blocks its rays reach (null: no paging, or the map
  /// paged in the scan's whole box first). Set beside page_in, which such a backend ignores but
  /// for the scans it hands to the CPU backend.
  const DevicePaging* device_paging = nullptr;
  /// A batch's next cloud (Map::insertSequence, Map::correctPoses): the backend may stage it
  /// while it works on this scan (the CUDA backend copies it into pinned memory while the
  /// device ray casts, then uploads it), for the next update, which gets that very cloud
  /// unchanged and marked ScanInput::cloud_staged. Null: nothing to stage.
  const PointCloud* stage_next = nullptr;
  /// With stage_next: the next scan's model is auto; its statistics may be gathered too
  /// (autoSensorStats() with `staged_ahead` then returns them).
  bool stage_next_auto_stats = false;
};

/// Which blocks a device view must hold: those of `keys` when set, else those in [lo, hi].
struct ViewScope {
  const std::vector<BlockKey>* keys = nullptr;
  BlockKey lo, hi;  ///< inclusive
};

class MapBackend {
 public:
  virtual ~MapBackend() = default;
  virtual const char* name() const = 0;

  /// Ray casts the scan (each cell updated at most once, hit wins) and applies the updates,
  /// stamping changed blocks with the revision. Fills the point and traversal counters and
  /// the prepare / ray cast / apply times of `stats`.
  void integrate(const ScanInput& scan, const UpdateSettings& how, BlockMap& blocks,
                 InsertStats& stats) {
    update(scan, ScanUpdate::kIntegrate, how, blocks, stats);
  }
  /// Walks the scan's rays again and undoes its updates (no block is created).
  void remove(const ScanInput& scan, const UpdateSettings& how, BlockMap& blocks,
              InsertStats& stats) {
    update(scan, ScanUpdate::kRemove, how, blocks, stats);
  }

  /// MapParams::dynamic: the points (sensor frame) of the last integrated scan that were
  /// classified dynamic (empty when the option is off).
  virtual const std::vector<Eigen::Vector3f>& lastDynamicPoints() const {
    static const std::vector<Eigen::Vector3f> kNone;
    return kNone;
  }
  virtual BlockCache& cache() = 0;
  const BlockCache& cache() const { return const_cast<MapBackend*>(this)->cache(); }

  /// Whether the backend pages in exactly the blocks its rays mark (UpdateSettings::page_in),
  /// so that the map need not page in the scan's whole box first.
  virtual bool pagesInMarkedBlocks() const { return false; }
  /// Whether the backend pages in what its rays reach itself through
  /// UpdateSettings::device_paging (keeping blocks of its own), so that the map need not page
  /// in the scan's whole box first.
  virtual bool reportsReachedBlocks() const { return false; }
  /// Whether the backend culls the blocks it needs itself (else the map's host culler runs
  /// over the host blocks in the frustum's box).
  virtual bool cullsOnItsOwn() const { return false; }
  /// Device memory the backend holds: its cache and its per-scan buffers.
  virtual size_t deviceBytes() const { return cache().deviceBytes(); }
  /// The paper's formula (1): the sensor's visible volume in blocks, as device bytes.
  virtual size_t deviceEstimateBytes() const { return 0; }
  /// Readers' access to the layers where the backend keeps them on a device (DESIGN §12): the
  /// read-only view over its device memory (device_layer_view.h), built after every existing
  /// host block of `scope` was made resident, showing map revision `revision`. False when the
  /// backend keeps no layers on a device (CPU) or cannot hold those blocks at once: the reader
  /// uses the host view (BlockView) instead. Not per product: every planning product and output
  /// reads the same view.
  virtual bool deviceView(const ViewScope& scope, BlockMap& blocks, uint64_t revision,
                          DeviceLayerView* out) {
    (void)scope, (void)blocks, (void)revision, (void)out;
    return false;
  }
  /// Device working memory lent with the backend's device views (nullptr when it has none):
  /// readers' buffers kept per map, not per process.
  virtual DeviceScratch* deviceScratch() { return nullptr; }
  /// The changed-block list of the backend's own memory: keys and state masks of the blocks it
  /// holds whose masks changed after `revision` and that the host map may not show yet (CUDA: a
  /// compaction over the device pool, no write-back of cells). False when its memory is the
  /// host map (CPU): the host change log then says everything.
  virtual bool masksChangedSince(uint64_t revision, std::vector<BlockKey>* keys,
                                 std::vector<BlockStateMasks>* masks) {
    (void)revision, (void)keys, (void)masks;
    return false;
  }
  /// The statistics an `auto` sensor model is resolved from (internal/auto_sensor.h) where the
  /// backend holds the points (CUDA: a reduction on the device beside the upload the scan needs
  /// anyway, which the scan's prepare then reuses: ScanInput::cloud_staged), with the same
  /// bits as gatherAutoSensorStats(). False when the backend has no such path (the map gathers
  /// them on the host). `staged_ahead`: the update just before staged this very cloud
  /// (UpdateSettings::stage_next); the statistics may come from that staging.
  virtual bool autoSensorStats(const PointCloud& cloud, AutoSensorStats* out, bool staged_ahead) {
    (void)cloud, (void)out, (void)staged_ahead;
    return false;
  }
  /// Where the host map's blocks are allocated (pinned memory for the CUDA backend).
  virtual std::shared_ptr<ChunkAllocator> hostAllocator() const { return plainChunkAllocator(); }

 protected:
  virtual void update(const ScanInput& scan, ScanUpdate what, const UpdateSettings& how,
                      BlockMap& blocks, InsertStats& stats) = 0;
};

}  // namespace fragg
