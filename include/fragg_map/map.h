// fragg::Map: the public face of the occupancy map.
//
//   fragg::MapParams params;                  // resolution, occupancy model, backend...
//   fragg::Map map(params);
//   map.insert(cloud, T_map_sensor, fragg::SensorModel::autoFromCloud(0.0, 30.0));
//   fragg::CellState s = map.query(p_map);
//   map.save("x.fgm");   fragg::Map m = fragg::Map::load("x.fgm");
//
// Readers see the map through forEachBlock / findBlock / changedBlocksSince (never the block
// storage); writers go through named edits (insert, remove, correctPoses, clearBox,
// writeCells, truncate, truncateOutside, merge, reset, load). Const members may run concurrently
// with each other (a CUDA write-back they need is serialised inside); a writer must exclude every
// other caller (fragg::LockedMap / the server's map lock does).
#pragma once

#include <Eigen/Geometry>
#include <cstdint>
#include <functional>
#include <map>
#include <memory>
#include <mutex>
#include <optional>
#include <string>
#include <vector>

#include "fragg_map/block_map.h"
#include "fragg_map/block_view.h"
#include "fragg_map/cell_writer.h"
#include "fragg_map/device_layer_view.h"
#include "fragg_map/device_scratch.h"
#include "fragg_map/insert_stats.h"
#include "fragg_map/map_params.h"
#include "fragg_map/occupancy.h"
#include "fragg_map/page_store.h"
#include "fragg_map/point_cloud.h"
#include "fragg_map/scan_store.h"
#include "fragg_map/sensor_model.h"
#include "fragg_map/submap.h"

namespace fragg {

class MapBackend;
struct ViewScope;
struct DevicePaging;
class Culler;
class Pager;
struct ScanRecord;
struct MapImage;
class HostViewGate;

/// One scan of a batch (Map::insertSequence): Map::insert's arguments. The cloud is not
/// copied; it must stay alive and unchanged during the call.
struct ScanToInsert {
  const PointCloud* cloud = nullptr;  ///< sensor frame
  Eigen::Isometry3d T_map_sensor = Eigen::Isometry3d::Identity();
  SensorModel sensor;
  int64_t stamp_ns = 0;
  std::string sensor_frame;
};

/// What a pose correction did (Map::correctPoses).
struct CorrectionStats {
  size_t scans = 0;
  InsertStats removal;    ///< the removals, summed
  InsertStats insertion;  ///< the re-insertions, summed
  double seconds_total = 0;
};

struct MemoryStats {
  size_t host_block_bytes = 0;  ///< cells + per-block metadata + index
  size_t device_bytes = 0;      ///< CUDA backend only
  /// CUDA: the sensor's frustum volume (paper formula (1)) in blocks, as device bytes.
  size_t device_estimate_bytes = 0;
  size_t blocks = 0;
  size_t known_voxels = 0;      ///< observed cells
  size_t scan_store_bytes = 0;  ///< kept scans' points in memory
};

/// A device layer view lent by Map::deviceView (device_layer_view.h): the view and the map's
/// view lock (one device view of a map at a time; the blocks it shows stay resident while it
/// lives). Hold the map's read lock as long as the lease.
class DeviceViewLease {
 public:
  DeviceViewLease(std::unique_lock<std::mutex> lock, const DeviceLayerView& view,
                  DeviceScratch& scratch)
      : lock_(std::move(lock)), view_(view), scratch_(&scratch) {}
  /// The view: device pointers, valid while this lease lives and the map is unchanged.
  [[nodiscard]] const DeviceLayerView& view() const { return view_; }
  /// The map's device working memory and stream on the view's device, the lease holder's
  /// alone while the lease lives (a reader's buffers are the map's, kept between calls).
  [[nodiscard]] DeviceScratch& scratch() const { return *scratch_; }

 private:
  std::unique_lock<std::mutex> lock_;
  DeviceLayerView view_;
  DeviceScratch* scratch_;
};

class Map {
 public:
  explicit Map(const MapParams& params = MapParams());
  ~Map();
  Map(Map&&) noexcept;
  Map& operator=(Map&&) noexcept;
  Map(const Map&) = delete;
  Map& operator=(const Map&) = delete;

  /// Integrates one scan. `cloud` is in the sensor frame; `T_map_sensor` places the sensor.
  /// Points the cloud marks free-only (PointCloud::free_only) only clear: free cells up to the
  /// point, the point's own cell not updated. Throws InvalidArgument for a non-finite pose, a
  /// bad sensor model or a free-only flag count other than the point count (map untouched).
  /// With `params.scans.keep` the scan is kept (the map integrates the kept points: the
  /// cloud itself by default, quantised ones with scans.point_step_m > 0) under its insertion
  /// index, `InsertStats::scan_id`, with `stamp_ns` and `sensor_frame` (the cloud's frame id, at
  /// most kMaxSensorFrameChars characters; kept for the caller, e.g. to find the scan's sensor
  /// again after loading the map). A kept scan with free-only points cannot be removed or
  /// corrected (the store keeps points, not flags).
  InsertStats insert(const PointCloud& cloud, const Eigen::Isometry3d& T_map_sensor,
                     const SensorModel& sensor, int64_t stamp_ns = 0,
                     const std::string& sensor_frame = std::string());
  /// MapParams::dynamic: the points of the last inserted scan (sensor frame, as given, after
  /// the height filter) that were classified dynamic and not inserted; empty when the option is
  /// off.
  [[nodiscard]] const std::vector<Eigen::Vector3f>& lastDynamicPoints_S() const;
  /// Inserts the scans in order, each as insert() would (the same cells, kept scans and
  /// statistics: one InsertStats per scan), while the backend overlaps a scan's host work with
  /// the device's work on the scan before: the CUDA backend copies the next cloud into pinned
  /// memory while the device ray casts, and uploads it (with the auto model's statistics)
  /// behind that scan. For a batch the caller already holds (a bag, a dataset, a replay); a
  /// height filter or quantised kept points (whose cloud is made during the insertion) run it
  /// without the overlap. Every scan's arguments are checked first (InvalidArgument, map
  /// untouched); a later failure (I/O while paging) leaves the scans before it inserted.
  std::vector<InsertStats> insertSequence(const std::vector<ScanToInsert>& scans);

  /// Loop closure: takes a kept scan out of the map, walking its rays again and undoing its
  /// updates (OccupancyModel::unapply says where that is exact). Throws InvalidArgument for an
  /// unknown index or a scan whose points are not kept (map untouched).
  InsertStats remove(ScanId id);
  /// Moves kept scans to corrected poses (T_map_sensor): every listed scan is removed first,
  /// then each is inserted again at its new pose, in index order. All arguments are checked
  /// before anything changes (InvalidArgument: unknown index, points not kept, pose not a
  /// finite rigid transform). Cost grows with the number of scans, not with the map.
  CorrectionStats correctPoses(const std::map<ScanId, Eigen::Isometry3d>& T_map_sensor_new);
  const ScanStore& scanStore() const { return *scan_store_; }

  /// With paging, const readers see the resident blocks only (call ensureResident first);
  /// on a non-const map query() and findCell() page the cell's block in.
  CellState query(const Eigen::Vector3d& p_map) const;
  CellState query(const Eigen::Vector3d& p_map);
  CellState state(const Cell& c) const { return model_.state(c); }
  const Cell* findCell(const VoxelKey& key) const;
  const Cell* findCell(const VoxelKey& key);
  VoxelKey keyOf(const Eigen::Vector3d& p_map) const;  ///< throws if beyond the int32 range
  Eigen::Vector3d centerOf(const VoxelKey& key) const;

  // Reading blocks. With the CUDA backend, device-side changes are written back first (a
  // write-back cache), so these always see the whole map.
  /// Read-only view of the blocks, valid until the map next changes; lock-free lookups.
  BlockView blockView() const { return BlockView(hostBlocks()); }
  /// The blocks as the host holds them now, without writing the device's changes back first
  /// (blockView() does). The same as blockView() on a CPU map. On a CUDA map, blocks changed on
  /// the device since the last write-back (blockView(), a save, an eviction) show their older
  /// cells and masks, and blocks made there since are missing. For readers that took their keys
  /// from a blockView() and accept cells that old (the server's paced outputs between their
  /// take-ins: a write-back of every changed block at every cloud cost a CUDA map's markers
  /// ~53 ms a cloud). Hold the map's read lock. The view pins the host's blocks while it lives:
  /// another reader's blockView() waits to write back until it is gone, and this thread gets a
  /// std::logic_error from blockView() while it holds one (a write-back would move the blocks
  /// under it); take blockView() first where both are needed.
  [[nodiscard]] BlockView hostBlockView() const;
  /// Whether a device holds changes the host's blocks lack (hostBlockView() shows them older;
  /// blockView() writes them back first). False on a CPU map.
  [[nodiscard]] bool deviceChangesPending() const;
  /// Writes back at most `max_blocks` (>= 1) of the blocks a device changed since the last
  /// write-back; true when more are left. For a reader about to read a CUDA map's changes of a
  /// long stretch (the frontier topics' mirror, after a frontier update of seconds): the whole
  /// write-back in one blockView() held insertion back for ~0.4 s on the GPU machine; in
  /// pieces, each under its own write lock, insertion waits for one piece at most. Hold the
  /// map's write lock (host blocks are made and written: no reader may hold a view).
  bool writeBackSome(size_t max_blocks);
  /// Calls fn(key, block) for every block, in unspecified order.
  void forEachBlock(const BlockVisitor& fn) const { blockView().forEach(fn); }
  /// Calls fn(key, block) for every block whose key lies in [lo, hi] (inclusive).
  void forEachBlockIn(const BlockKey& lo, const BlockKey& hi, const BlockVisitor& fn) const {
    blockView().forEachIn(lo, hi, fn);
  }
  /// nullptr when the block does not exist (all its cells unknown).
  const Block* findBlock(const BlockKey& key) const { return blockView().findBlock(key); }
  /// The block's cell-state masks (occupied / free; unknown = neither), nullptr when the block
  /// does not exist. Equal to stateMasksOf(*findBlock(key), model()) after every write.
  [[nodiscard]] const BlockStateMasks* findMasks(const BlockKey& key) const {
    return blockView().findMasks(key);
  }
  size_t blockCount() const { return blockView().size(); }
  /// Keys of the blocks whose cells changed (`what`) after map revision `revision` (what
  /// markers, frontiers and incremental outputs use); revision() read with the blocks is where
  /// the next call starts. Removed blocks are not listed. BlockChange::kMasks (the blocks whose
  /// state masks changed) comes from the change log the integrator and the edits keep, not from
  /// a walk over the blocks, unless the question reaches back past the log's oldest record.
  std::vector<BlockKey> changedBlocksSince(uint64_t revision,
                                           BlockChange what = BlockChange::kAny) const {
    return blockView().changedSince(revision, what);
  }

  /// The changed-block list (DESIGN §12): keys and current state masks of every block whose
  /// masks changed after map revision `revision`, each once, in unspecified order, without
  /// reading a cell: from the host change log and, where the backend keeps blocks on a device,
  /// a compaction over its pool (no write-back). Blocks erased since are not listed. False
  /// (nothing written) when the log no longer reaches back that far: walk the map instead.
  [[nodiscard]] bool masksChangedSince(uint64_t revision, std::vector<BlockKey>* keys,
                                       std::vector<BlockStateMasks>* masks) const;

  /// The read-only device view of the layers (device_layer_view.h) holding every existing
  /// block of `keys`, for readers with kernels (planning's CUDA part); nullptr when the backend
  /// keeps no layers on a device (CPU) or cannot hold those blocks at once: read the host view
  /// (blockView) instead. Blocks the view lacks have no cell observed. Hold the map's read lock.
  [[nodiscard]] std::unique_ptr<DeviceViewLease> deviceView(
      const std::vector<BlockKey>& keys) const;
  /// The same for every existing block whose key lies in [lo, hi] (inclusive).
  [[nodiscard]] std::unique_ptr<DeviceViewLease> deviceView(const BlockKey& lo,
                                                            const BlockKey& hi) const;

  // Named edits besides insertion and correction.
  /// Makes every cell in the box unknown (block-granular memory release where possible).
  /// Kept scans that could reach into the box can no longer be removed or corrected.
  void clearBox(const Eigen::Vector3d& min_map, const Eigen::Vector3d& max_map);
  /// octomap_server's clear_bbx rule: every observed cell whose key lies in the box (the keys
  /// of min_map and max_map, inclusive, as clearBox) is set to the lower clamp (free, log-odds
  /// clamp_min; hit counts kept); unknown cells stay unknown. Returns the cells set. Same
  /// argument checks as clearBox (InvalidArgument, nothing changed); kept scans that could
  /// reach into the box can no longer be removed or corrected.
  uint64_t freeBox(const Eigen::Vector3d& min_map, const Eigen::Vector3d& max_map);
  /// Writes cells directly (importers, test fixtures): `edit` gets a CellWriter. Bumps the
  /// revision once; every kept scan can no longer be removed or corrected afterwards.
  void writeCells(const std::function<void(CellWriter&)>& edit);
  void reset();

  // Sub-maps (fragg_map/submap.h; src/core/submap.cpp). A cell belongs to a region by its
  // centre. The sub-map has this map's resolution and occupancy model, `backend`, no kept
  // scans, and region() = where it was cut from (saved in its .fgm). All arguments are checked
  // before anything changes (InvalidArgument: non-finite or inverted box, negative or NaN
  // radius, a box beyond the key range).
  /// Copies of the cells whose centres lie in [min_map, max_map]; this map is unchanged.
  Map extract(const Eigen::Vector3d& min_map, const Eigen::Vector3d& max_map,
              Backend backend = Backend::kCpu, SubmapStats* stats = nullptr) const;
  /// The same, paging the box's blocks in first (a const map extracts its resident blocks).
  Map extract(const Eigen::Vector3d& min_map, const Eigen::Vector3d& max_map,
              Backend backend = Backend::kCpu, SubmapStats* stats = nullptr);
  /// Copies of the cells whose centres are farther than radius_m from center_map (what
  /// truncateOutside moves); this map is unchanged.
  Map extractOutside(const Eigen::Vector3d& center_map, double radius_m,
                     Backend backend = Backend::kCpu, SubmapStats* stats = nullptr) const;
  /// Moves those cells out: they become unknown here and blocks left empty are erased. Kept
  /// scans whose rays could reach into the box can no longer be removed or corrected (as
  /// clearBox).
  Map truncate(const Eigen::Vector3d& min_map, const Eigen::Vector3d& max_map,
               Backend backend = Backend::kCpu, SubmapStats* stats = nullptr);
  /// Moves out every cell whose centre is farther than radius_m from center_map (the map keeps
  /// the ball). Kept scans whose rays could reach beyond the sphere become unremovable.
  Map truncateOutside(const Eigen::Vector3d& center_map, double radius_m,
                      Backend backend = Backend::kCpu, SubmapStats* stats = nullptr);
  /// Merges `sub` into this map (MergeMode says how two cells combine). Without T_map_sub
  /// (or with a pose that is a whole-cell translation: rotation identity within 1e-9, each
  /// translation component an integer number of voxels within 1e-6 voxel) cells are shifted
  /// key for key, exactly. Any other pose resamples: every map cell whose centre, mapped back
  /// by T_map_sub^-1 into the sub-map, falls in an observed sub-map cell (the nearest cell:
  /// the one containing that point) takes that cell's value. Throws InvalidArgument (map
  /// untouched) for a different resolution or occupancy model (prob_hit, prob_miss, clamps),
  /// or a pose that is not a finite rigid transform. Kept scans whose rays could reach the
  /// merged region can no longer be removed or corrected.
  SubmapStats merge(const Map& sub, MergeMode mode,
                    const std::optional<Eigen::Isometry3d>& T_map_sub = std::nullopt);
  /// Where this map was cut from (kNone for a whole map).
  const SubmapRegion& region() const { return region_; }
  /// Validates and sets the region (saved with the map).
  void setRegion(const SubmapRegion& region);

  const MapParams& params() const { return params_; }
  const OccupancyModel& model() const { return model_; }
  double resolution() const { return params_.resolution_m; }
  uint64_t revision() const { return revision_; }
  /// Changes whenever blocks leave or join the map's view other than through their cells
  /// changing: erased (clearBox, truncate, reset) or paged out or in. changedBlocksSince()
  /// lists neither, so incremental readers (frontiers) recompute everything when it differs
  /// from the value they last saw. Unique across maps: a new or loaded map never has the
  /// value of another map.
  uint64_t viewEpoch() const { return view_epoch_; }
  size_t scanCount() const { return scans_; }
  const char* backendName() const;
  /// Why that backend ("auto: CUDA device 0 (...)", "auto: CPU backend (no CUDA device)").
  const std::string& backendReason() const { return backend_reason_; }

  /// Memory and counts of the whole map: on a CUDA map the device's changes are written back
  /// first, and known_voxels walks every cell of the live blocks, in slot order on the map's
  /// threads (W1 at 5 cm after 40 clouds, 212 k blocks: 11 ms on 2 cores).
  MemoryStats memory() const;
  /// What memory() says without a write-back or a walk over the cells: the host's copy of the
  /// blocks as it stands (host_block_bytes), the device's bytes and estimate, the kept scans;
  /// `blocks` and `known_voxels` are left 0 (they need every block: memory(), or a reader that
  /// keeps the blocks' state masks, as the server's mask mirror).
  [[nodiscard]] MemoryStats memoryAsHeld() const;
  size_t knownVoxelCount() const;
  KeyBounds bounds() const { return hostBlocks().observedBounds(); }

  /// Writes the whole map, paged-out blocks included (read from the store).
  void save(const std::string& path) const;
  /// A copy of what save() writes, for writeMapImage (map_image.h) to compress and write
  /// without the map (a memory copy of the blocks: what an autosave takes under the read
  /// lock). InvalidArgument for a paged map (its store is the map; the copy would bring every
  /// block into RAM).
  MapImage image() const;
  /// Reads a .fgm file into a new map integrating with `backend` (other settings default; the
  /// map keeps scans if the file has them).
  static Map load(const std::string& path, Backend backend = Backend::kAuto);
  /// The same, with every setting that is not in the file (backend, threads, ray cast, CUDA,
  /// scan store...) from `runtime`; the file gives the resolution and the occupancy model. The
  /// file's kept scans are loaded only when `runtime.scans.keep`.
  static Map load(const std::string& path, const MapParams& runtime);

  // Out-of-core paging (fragg_map/page_store.h; src/core/pager.cpp, map_paging.cpp). The store
  // is the map: every block is committed to it (dirty blocks every policy.commit_every_scans
  // scans or commit_every_s seconds, before blocks are paged out, and at close) together with
  // the number of scans they hold; blocks beyond the budget leave RAM, least recently used
  // first, blocks within policy.radius_m of the last sensor position last. Commits are written
  // by a background thread (policy.background_writer) while the map goes on; a block paged out
  // before its commit is written is read back from that commit. Insertion, removal,
  // correction, clearBox, truncate, merge and writeCells page in what they reach first; const
  // readers see the resident blocks (ensureResident brings a box back). Kept scans are not
  // stored: a map that keeps scans cannot page (InvalidArgument).
  /// Attaches a store to this map. A new (empty) store receives the whole map at once. A store
  /// that already holds a map is continued: this map must be empty and have the same resolution
  /// and occupancy model (InvalidArgument), and takes the store's blocks (paged out) and scan
  /// count. IoError when the store cannot be read or written.
  void attachPageStore(std::shared_ptr<PageStore> store, const PagingPolicy& policy);
  /// A map continuing the one a store holds: resolution and occupancy model from the store,
  /// everything else from `runtime`. IoError for a store that holds no map.
  static Map openPageStore(std::shared_ptr<PageStore> store, const MapParams& runtime,
                           const PagingPolicy& policy);
  /// The map a store holds, read whole into RAM from one snapshot (no paging; the store is
  /// only read, so another process may be writing it). Every record is checked (IoError).
  static Map loadPageStore(PageStore& store, const MapParams& runtime = MapParams());
  /// Brings every paged-out block whose cells may lie in the box back into RAM.
  void ensureResident(const Eigen::Vector3d& min_map, const Eigen::Vector3d& max_map);
  void ensureAllResident();
  /// Commits the dirty blocks and the scan count now; they are in the store when it returns.
  void commitPages();
  bool paging() const { return pager_ != nullptr; }
  PagingStats pagingStats() const;

 private:
  static Map loadFile(const std::string& path, const MapParams& runtime, bool keep_as_file);
  /// save() and image(): the file's header for `block_count` blocks, and what follows the
  /// blocks (region, kept scans) appended to `out`.
  void encodeHeader(std::vector<uint8_t>* out, uint64_t block_count) const;
  void encodeTail(std::vector<uint8_t>* out) const;
  /// Paging: brings the paged-out blocks of [lo, hi] back (the backend's cache over them
  /// invalidated first) and marks the box as used now.
  void pageInBlocks(const BlockKey& lo, const BlockKey& hi);
  void pageInAllBlocks();
  /// Pages in the blocks of `keys` that are paged out (the backend's exact page-in).
  void pageInKeys(const std::vector<BlockKey>& keys);
  /// pageInKeys for `keys` and the 26 blocks around each that exist (resident or paged out):
  /// the blocks MapParams::dynamic's rules read around the cells a scan touches.
  void pageInKeysAndNeighbours(const std::vector<BlockKey>& keys);
  /// Paging for a backend that reports the blocks its rays reach (DevicePaging, map_paging.cpp);
  /// `*read` counts the blocks it reads back.
  DevicePaging devicePaging(size_t* read);
  /// DevicePaging::make_room's work (`in_scan`: a stop inside the scan, else the read-ahead);
  /// returns the blocks read back.
  size_t makeDeviceRoom(const std::vector<BlockKey>& reached, const std::vector<BlockKey>& pinned,
                        size_t new_blocks, bool in_scan);
  /// Paging on a device backend, before its ray pass: reads back the paged-out regions the
  /// scan's rays pass through (walked on the host, region_reach.h; [lo, hi] their block box),
  /// making room with the regions they reach held; `*read` counts the blocks read back.
  void pageInAhead(const PointCloud& cloud, const ScanRecord& how, const BlockKey& lo,
                   const BlockKey& hi, size_t* read);
  /// Paging after a scan (or removal): commits when due or over budget, then pages out.
  void pageAfterScan(const Eigen::Vector3d& sensor_map);
  /// After paging out: the memory of the blocks that left goes back to the system.
  void releasePagedOutMemory();
  /// Commits (at close and before a move-assignment); errors are logged, not thrown.
  void closePaging() noexcept;
  void fallBackToCpu(const std::string& why);
  /// The host map, complete (the backend's cache written back first; serialised).
  const BlockMap& hostBlocks() const;
  /// InvalidArgument unless the map keeps scans, `id` is one of them and it is removable.
  void requireRemovable(ScanId id) const;
  /// The start of clearBox / freeBox: checks the corners (InvalidArgument), pages the box in,
  /// drops the device's copies, marks the kept scans it touches, bumps the revision; returns the
  /// blocks in the box and its corner keys.
  std::vector<BlockIndex> beginBoxEdit(const Eigen::Vector3d& min_map,
                                       const Eigen::Vector3d& max_map, VoxelKey* lo, VoxelKey* hi);
  /// Marks the kept scans whose rays could reach into the box as no longer removable.
  void markScansTouching(const Eigen::Vector3d& min_map, const Eigen::Vector3d& max_map);
  /// Marks the kept scans for which `reaches(sensor origin, reach_m)` holds, reach_m bounding
  /// how far the scan's rays go from its sensor.
  void markScansWhere(
      const std::function<bool(const Eigen::Vector3d& origin_map, double reach_m)>& reaches);
  /// Makes the cells of `blocks` for which `inside` holds unknown, stamps the blocks that lost
  /// an observed cell with revision_ (bumped by the caller, after the cache was invalidated
  /// over them) and erases the blocks left empty. Returns the observed cells cleared.
  uint64_t clearCellsWhere(const std::vector<BlockIndex>& blocks,
                           const std::function<bool(const VoxelKey&)>& inside,
                           uint64_t* blocks_erased = nullptr);
  /// extract: copies of the cells of `region` in a new map holding `region`.
  Map copyRegion(const SubmapRegion& region, Backend backend, SubmapStats* stats) const;
  /// truncate / truncateOutside: copyRegion, then those cells cleared here (cache
  /// invalidated over the region first, kept scans reaching it marked).
  Map moveOut(const SubmapRegion& region, Backend backend, SubmapStats* stats);
  /// Culling and integration of one prepared scan (insert or remove) with its own ray cast
  /// mode and no-return setting. `host_cull`: run the host culler for a backend that does not
  /// cull on its own (counters only; corrections skip it). `cloud_staged`: the backend's
  /// autoSensorStats() saw this cloud just before (ScanInput::cloud_staged).
  /// `stage_next`, `stage_next_auto_stats`: UpdateSettings' (the batch's next cloud).
  InsertStats integrateScan(const PointCloud& cloud, const ScanRecord& how, bool remove,
                            bool host_cull, bool cloud_staged = false,
                            const PointCloud* stage_next = nullptr,
                            bool stage_next_auto_stats = false);
  /// insert() after its arguments were checked. `staged_ahead`: the update just before staged
  /// this cloud (UpdateSettings::stage_next); `next`: the batch's next scan, or null.
  InsertStats insertChecked(const PointCloud& cloud, const Eigen::Isometry3d& T_map_sensor,
                            const SensorModel& sensor, int64_t stamp_ns,
                            const std::string& sensor_frame, bool staged_ahead,
                            const ScanToInsert* next);

  // Every member is moved by operator=(Map&&) in map.cpp (it commits the paging first): a new
  // member goes there too.
  MapParams params_;
  OccupancyModel model_;
  std::unique_ptr<MapBackend> backend_;
  std::string backend_reason_;
  // The host copy may lag the backend's cache; hostBlocks() synchronises it, hence mutable.
  mutable BlockMap blocks_;
  /// Serialises that write-back between concurrent readers (a pointer: Map is movable).
  std::unique_ptr<std::mutex> sync_mutex_;
  /// Pinned by every hostBlockView(): a reader's write-back waits until no such view is read
  /// (host_view_gate.h). Shared: the views keep it alive.
  std::shared_ptr<HostViewGate> host_view_gate_;
  /// The backend's changes written into blocks_ (under sync_mutex_) once no hostBlockView() is
  /// held; nothing when none is pending. The caller holds neither sync_mutex_ nor a view.
  void writeBack() const;
  /// Held by a DeviceViewLease: one device view at a time (its blocks stay resident).
  std::unique_ptr<std::mutex> view_mutex_;
  /// deviceView() with its scope.
  std::unique_ptr<DeviceViewLease> deviceViewOf(const ViewScope& scope) const;
  std::unique_ptr<Culler> culler_;
  uint64_t revision_ = 0;
  uint64_t view_epoch_ = 0;
  /// A new value for view_epoch_ (from a process-wide counter).
  void bumpViewEpoch();
  size_t scans_ = 0;
  ScanId next_scan_id_ = 0;
  std::unique_ptr<ScanStore> scan_store_;
  SubmapRegion region_;
  std::unique_ptr<Pager> pager_;
};

}  // namespace fragg
