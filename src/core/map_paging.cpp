// Map's side of out-of-core paging: attaching a store, paging blocks in and out, commits.
#include <chrono>
#ifdef __GLIBC__
#include <malloc.h>
#endif
#include <algorithm>
#include <cmath>
#include <string>
#include <unordered_set>
#include <vector>

#include "fragg_map/errors.h"
#include "fragg_map/internal/backend.h"
#include "fragg_map/internal/pager.h"
#include "fragg_map/internal/region_reach.h"
#include "fragg_map/internal/seconds_since.h"
#include "fragg_map/log.h"
#include "fragg_map/map.h"

namespace fragg {

namespace {
bool sameModel(const MapParams& p, const StoreMapMeta& m) {
  return p.resolution_m == m.resolution_m && p.occupancy == m.occupancy;
}

StoreMapMeta metaOf(const MapParams& p, uint64_t scans) {
  StoreMapMeta m;
  m.resolution_m = p.resolution_m;
  m.occupancy = p.occupancy;
  m.scans = scans;
  return m;
}

InvalidArgument scanTooLarge(size_t needed, size_t block_bytes, double budget_mb) {
  const double needed_mb = static_cast<double>(needed * block_bytes) / (1024.0 * 1024.0);
  return InvalidArgument("paging: one scan needs " + std::to_string(needed) +
                         " blocks resident (the regions its rays reach, " +
                         std::to_string(needed_mb) + " MB) but the paging budget is " +
                         std::to_string(budget_mb) +
                         " MB: raise the budget; the scan was not integrated");
}

BlockKey clampedBlockOf(const Eigen::Vector3d& p_map, double resolution_m) {
  const Eigen::Vector3d v =
      (p_map / resolution_m).array().floor().cwiseMax(-2147483648.0).cwiseMin(2147483647.0);
  return blockKeyOf(VoxelKey{static_cast<int32_t>(v.x()), static_cast<int32_t>(v.y()),
                             static_cast<int32_t>(v.z())});
}
}  // namespace

void Map::attachPageStore(std::shared_ptr<PageStore> store, const PagingPolicy& policy) {
  if (!store) throw InvalidArgument("no page store given");
  if (pager_) throw InvalidArgument("this map already pages to " + pager_->store().path());
  policy.validate();
  if (params_.scans.keep || scan_store_->size() > 0)
    throw InvalidArgument("a map that keeps its scans cannot page (the store holds no scans)");
  if (params_.dynamic.decay_log_odds_per_scan > 0.0)
    throw InvalidArgument(
        "a map with dynamic.decay_log_odds_per_scan cannot page (paged-out blocks would not "
        "decay)");
  const std::vector<uint8_t> meta_bytes = store->readMeta();
  if (!meta_bytes.empty()) {
    const StoreMapMeta meta = decodeStoreMeta(meta_bytes, store->path());
    if (!sameModel(params_, meta))
      throw InvalidArgument(store->path() +
                            ": the store's map has another resolution or occupancy model");
    if (!blocks_.empty() || scans_ > 0)
      throw InvalidArgument(store->path() +
                            ": the store already holds a map: continue it from an empty map "
                            "(Map::openPageStore)");
    backend_->cache().invalidateAll(blocks_);
    pager_ = std::make_unique<Pager>(std::move(store), policy, params_.resolution_m);
    pager_->reserveSlots(blocks_);  // the arrays never grow under the budget
    pager_->setCommitted(meta.scans, revision_);
    scans_ = meta.scans;
    next_scan_id_ = meta.scans;
    ++revision_;
    return;
  }
  if (!store->keys().empty())
    throw IoError(store->path() + ": the store holds blocks but no map metadata");
  writeBack();
  auto pager = std::make_unique<Pager>(std::move(store), policy, params_.resolution_m);
  pager->reserveSlots(blocks_);  // the arrays never grow under the budget
  pager->markAllDirty();
  pager->commit(blocks_, revision_, metaOf(params_, scans_));
  pager->flush();
  pager_ = std::move(pager);
}

Map Map::openPageStore(std::shared_ptr<PageStore> store, const MapParams& runtime,
                       const PagingPolicy& policy) {
  if (!store) throw InvalidArgument("no page store given");
  const std::vector<uint8_t> meta_bytes = store->readMeta();
  if (meta_bytes.empty()) throw IoError(store->path() + ": the page store holds no map");
  const StoreMapMeta meta = decodeStoreMeta(meta_bytes, store->path());
  MapParams params = runtime;
  params.resolution_m = meta.resolution_m;
  params.occupancy = meta.occupancy;
  Map map(params);
  map.attachPageStore(std::move(store), policy);
  return map;
}

Map Map::loadPageStore(PageStore& store, const MapParams& runtime) {
  const std::vector<uint8_t> first = store.readMeta();
  if (first.empty()) throw IoError(store.path() + ": the page store holds no map");
  const StoreMapMeta meta = decodeStoreMeta(first, store.path());
  MapParams params = runtime;
  params.resolution_m = meta.resolution_m;
  params.occupancy = meta.occupancy;
  params.scans.keep = false;
  try {
    params.validate();
  } catch (const InvalidArgument& e) {
    throw IoError(store.path() + ": bad parameters in the page store: " + e.what());
  }
  Map map(params);
  const OccupancyModel& model = map.model();
  const std::vector<uint8_t> last = store.readAll([&](const BlockKey& key, const Block& block) {
    for (const Cell& c : block.cells) {
      if (c.hits < 0) throw IoError(store.path() + ": negative hit count in a block record");
      if (c.observed() && (c.log_odds_fx < model.min_fx || c.log_odds_fx > model.max_fx))
        throw IoError(store.path() + ": log-odds outside the clamping range in a block record");
    }
    bool created = false;
    const BlockIndex i = map.blocks_.findOrCreate(key, &created, /*initialise=*/false);
    if (!created) throw IoError(store.path() + ": duplicate block record");
    map.blocks_.block(i) = block;
    map.blocks_.masks(i) = stateMasksOf(block, model);
  });
  const StoreMapMeta at_read = decodeStoreMeta(last, store.path());
  map.scans_ = static_cast<size_t>(at_read.scans);
  map.next_scan_id_ = at_read.scans;
  map.revision_ = 1;
  return map;
}

void Map::pageInBlocks(const BlockKey& lo, const BlockKey& hi) {
  if (!pager_) return;
  pager_->touch(lo, hi, scans_ + 1);
  if (!pager_->anyPagedOut(lo, hi)) return;
  // A paged-out block has no copy in the backend's cache (forget() took it when it left):
  // the blocks read back are new host blocks to the cache, the rest of its copies stay.
  const std::vector<BlockIndex> read = pager_->pageIn(lo, hi, blocks_);
  blocks_.recomputeMasks(read, model_);  // the store keeps cells only
  backend_->cache().added(read, blocks_);
  bumpViewEpoch();
}

void Map::pageInKeysAndNeighbours(const std::vector<BlockKey>& keys) {
  if (!pager_) return;
  // Neighbours that exist nowhere stay out: pageInKeys counts a missing key as a block the
  // scan creates (room is reserved for it).
  std::vector<BlockKey> all(keys);
  all.reserve(keys.size() * 2);
  for (const BlockKey& k : keys)
    for (int dz = -1; dz <= 1; ++dz)
      for (int dy = -1; dy <= 1; ++dy)
        for (int dx = -1; dx <= 1; ++dx) {
          if (dx == 0 && dy == 0 && dz == 0) continue;
          const BlockKey n{k.x + dx, k.y + dy, k.z + dz};
          if (blocks_.find(n) != kNoBlock || pager_->isPagedOut(n)) all.push_back(n);
        }
  std::sort(all.begin(), all.end(), storeOrder);
  all.erase(std::unique(all.begin(), all.end()), all.end());
  pageInKeys(all);
}

void Map::pageInKeys(const std::vector<BlockKey>& keys) {
  if (!pager_) return;
  // The budget is a hard limit: `keys` are every block this scan's rays mark (CPU backend),
  // before any of its changes is applied. The paged-out blocks of their regions come back and
  // the missing ones are created; room is made for both first, from the other regions (clean
  // ones first, then changed ones, held as records for the next commit). When the scan's
  // regions alone exceed the budget the scan is refused: nothing has changed yet.
  size_t fresh = 0;
  std::vector<BlockKey> wanted = pager_->pagedOutOfRegions(keys, blocks_, &fresh);
  const size_t incoming = wanted.size() + fresh;
  const auto t0 = std::chrono::steady_clock::now();
  const bool round = pager_->excessOverBudget(blocks_.size() + incoming) > 0;
  if (round) {
    const Eigen::Vector3d sensor = pager_->lastSensor();
    std::vector<BlockIndex> out =
        pager_->victims(blocks_, sensor, /*clean_only=*/true, incoming, &keys);
    if (pager_->excessOverBudget(blocks_.size() - out.size() + incoming) > 0)
      out = pager_->victims(blocks_, sensor, /*clean_only=*/false, incoming, &keys);
    const auto t_evict = std::chrono::steady_clock::now();
    backend_->cache().forget(out, blocks_);  // the insertion holds sync_mutex_ already
    pager_->stageCounters().seconds_evict += secondsSince(t_evict);
    pager_->pageOut(out, blocks_);
    ++pager_->stageCounters().rounds_in_scan;
  }
  // The kept records make way for the blocks (they never push a block out).
  if (!pager_->dropRecordsToFit(blocks_.size() + incoming))
    throw scanTooLarge(blocks_.size() + incoming, pager_->blockBytes(), pager_->policy().budget_mb);
  if (round)
    pager_->notePageOutSeconds(
        std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count());
  pager_->noteScanIncoming(incoming);
  pager_->reserveBlocks(fresh);
  std::vector<BlockIndex> read;
  try {
    read = pager_->readBack(std::move(wanted), blocks_);
  } catch (...) {
    pager_->reserveBlocks(0);
    throw;
  }
  pager_->noteResident(blocks_.size() + fresh);
  pager_->reserveBlocks(0);
  blocks_.recomputeMasks(read, model_);  // the store keeps cells only
  if (read.empty()) return;
  backend_->cache().added(read, blocks_);
  bumpViewEpoch();
}

DevicePaging Map::devicePaging(size_t* read) {
  // The budget counts the host map and the blocks the backend holds that the host map lacks
  // (created on the device since the last write-back): both are resident.
  DevicePaging paging;
  paging.paged_out_regions = [this](const BlockKey& lo, const BlockKey& hi) {
    std::vector<std::pair<BlockKey, BlockKey>> boxes;
    for (const BlockKey& r : pager_->pagedOutRegionsIn(lo, hi)) {
      const BlockKey first = firstBlockOf(r);
      boxes.emplace_back(
          first, BlockKey{first.x | kRegionMask, first.y | kRegionMask, first.z | kRegionMask});
    }
    return boxes;
  };
  paging.room = [this] {
    return pager_->roomFor(blocks_.size() + backend_->cache().blocksNotInHostMap());
  };
  paging.make_room = [this, read](const std::vector<BlockKey>& reached,
                                  const std::vector<BlockKey>& pinned, size_t new_blocks) {
    // A stop inside the scan (its pass is redone after it): counted apart from the read-ahead.
    const auto t0 = std::chrono::steady_clock::now();
    PagingStats& c = pager_->stageCounters();
    const size_t back = makeDeviceRoom(reached, pinned, new_blocks, /*in_scan=*/true);
    ++c.stops_in_scan;
    c.blocks_read_in_scan += back;
    c.seconds_in_scan += secondsSince(t0);
    *read += back;
  };
  return paging;
}

size_t Map::makeDeviceRoom(const std::vector<BlockKey>& reached,
                           const std::vector<BlockKey>& pinned, size_t new_blocks, bool in_scan) {
  // As pageInKeys, with the backend's own blocks counted and its scan's blocks pinned: the
  // scan runs on (the insertion holds sync_mutex_), nothing of it is applied yet.
  PagingStats& counters = pager_->stageCounters();
  size_t own = backend_->cache().blocksNotInHostMap();
  std::vector<BlockKey> wanted = pager_->pagedOutOfRegions(reached, blocks_, nullptr);
  const size_t incoming = wanted.size() + new_blocks;
  const bool round = pager_->excessOverBudget(blocks_.size() + own + incoming) > 0;
  std::chrono::steady_clock::time_point t0;  // page-out: after the write-back (seconds_sync)
  if (round) {
    // The blocks earlier scans made on the device get their host blocks first, so that they
    // can leave too (between commits they would fill the budget); this scan's, not applied
    // yet, stay on the device.
    const auto t_sync = std::chrono::steady_clock::now();
    backend_->cache().sync(blocks_);
    t0 = std::chrono::steady_clock::now();
    const double sync_s = std::chrono::duration<double>(t0 - t_sync).count();
    pager_->noteSyncSeconds(sync_s);
    if (in_scan) counters.seconds_sync_in_scan += sync_s;
    own = backend_->cache().blocksNotInHostMap();
    std::vector<BlockKey> held = pinned;
    held.insert(held.end(), reached.begin(), reached.end());
    const Eigen::Vector3d sensor = pager_->lastSensor();
    std::vector<BlockIndex> out =
        pager_->victims(blocks_, sensor, /*clean_only=*/true, own + incoming, &held);
    if (pager_->excessOverBudget(blocks_.size() - out.size() + own + incoming) > 0)
      out = pager_->victims(blocks_, sensor, /*clean_only=*/false, own + incoming, &held);
    const auto t_evict = std::chrono::steady_clock::now();
    backend_->cache().forget(out, blocks_);
    counters.seconds_evict += secondsSince(t_evict);
    pager_->pageOut(out, blocks_);
    ++(in_scan ? counters.rounds_in_scan : counters.rounds_between_scans);
  }
  if (round) pager_->notePageOutSeconds(secondsSince(t0));
  if (in_scan) {
    const size_t needed = blocks_.size() + own + incoming;
    // The rays stop at the budget's room (the pass is redone after this): a scan that still
    // has no room for its new blocks beside the held records would never finish.
    if (!pager_->dropRecordsToFit(needed) ||
        pager_->roomFor(blocks_.size() + own + wanted.size()) < new_blocks)
      throw scanTooLarge(needed, pager_->blockBytes(), pager_->policy().budget_mb);
  } else {
    // Ahead of the pass `new_blocks` is an estimate: room made for it where it can be. When
    // the reads themselves do not fit beside the held records nothing is read ahead: the pass
    // stops for them and decides (reads with the room it makes, or refuses the scan).
    const size_t resident = blocks_.size() + own;
    if (!pager_->dropRecordsToFit(resident + wanted.size()) ||
        pager_->roomFor(resident) < wanted.size())
      return 0;
  }
  pager_->reserveBlocks(own + (in_scan ? new_blocks : 0));
  std::vector<BlockIndex> back;
  try {
    back = pager_->readBack(std::move(wanted), blocks_);
  } catch (...) {
    pager_->reserveBlocks(0);
    throw;
  }
  pager_->reserveBlocks(0);
  pager_->noteResident(blocks_.size() + own);
  if (back.empty()) return 0;
  blocks_.recomputeMasks(back, model_);  // the store keeps cells only
  backend_->cache().added(back, blocks_);
  bumpViewEpoch();
  return back.size();
}

void Map::pageInAhead(const PointCloud& cloud, const ScanRecord& how, const BlockKey& lo,
                      const BlockKey& hi, size_t* read) {
  // The CPU path pages in exactly the blocks its rays mark before it applies any; the device's
  // rays run on the device, so the regions they pass through are walked here first (at region
  // granularity; up to PagingPolicy::read_ahead_rays rays, an even sample of a denser scan): the
  // paged-out ones are read back and the resident ones pinned while room is made. A region the walk
  // misses (reached by rays between the sample's, at a corner in float, a no-return ray) is still
  // caught by the pass (a miss, read back, the pass redone).
  const auto t0 = std::chrono::steady_clock::now();
  const std::vector<BlockKey> paged_regions = pager_->pagedOutRegionsIn(lo, hi);
  PagingStats& c = pager_->stageCounters();
  if (paged_regions.empty()) {
    c.seconds_reach += secondsSince(t0);
    return;
  }
  const std::unordered_set<BlockKey, BlockKeyHash> paged(paged_regions.begin(),
                                                         paged_regions.end());
  const double region_m = params_.resolution_m * kBlockSize * (1 << kRegionBits);
  const std::vector<BlockKey> regions =
      regionsReached(cloud, how.T_map_sensor, how.model.max_range_m, region_m, regionOf(lo),
                     regionOf(hi), params_.threads, pager_->policy().read_ahead_rays);
  std::vector<BlockKey> reached, pinned;
  for (const BlockKey& r : regions) (paged.count(r) ? reached : pinned).push_back(firstBlockOf(r));
  c.seconds_reach += secondsSince(t0);
  if (reached.empty()) return;
  const auto t1 = std::chrono::steady_clock::now();
  // Room for the blocks the rays will create too, as many as the last scan brought in (as
  // Map::pageAfterScan reckons): the pass then rarely stops for the budget's room, and a round
  // needed here runs with every region the rays reach held.
  const size_t back =
      makeDeviceRoom(reached, pinned, pager_->lastScanIncoming(), /*in_scan=*/false);
  c.scans_read_ahead += back > 0;
  c.blocks_read_ahead += back;
  c.seconds_read_ahead += secondsSince(t1);
  *read += back;
}

void Map::pageInAllBlocks() {
  if (!pager_ || pager_->pagedOutCount() == 0) return;
  const std::vector<BlockIndex> read = pager_->pageInAll(blocks_);
  blocks_.recomputeMasks(read, model_);  // the store keeps cells only
  backend_->cache().added(read, blocks_);
  bumpViewEpoch();
}

void Map::ensureResident(const Eigen::Vector3d& min_map, const Eigen::Vector3d& max_map) {
  if (!min_map.allFinite() || !max_map.allFinite())
    throw InvalidArgument("box corners must be finite");
  if ((min_map.array() > max_map.array()).any())
    throw InvalidArgument("box min corner must not exceed the max corner");
  pageInBlocks(clampedBlockOf(min_map, params_.resolution_m),
               clampedBlockOf(max_map, params_.resolution_m));
}

void Map::ensureAllResident() { pageInAllBlocks(); }

Map Map::extract(const Eigen::Vector3d& min_map, const Eigen::Vector3d& max_map, Backend backend,
                 SubmapStats* stats) {
  if (pager_ && min_map.allFinite() && max_map.allFinite() &&
      (min_map.array() <= max_map.array()).all())
    ensureResident(min_map, max_map);
  return static_cast<const Map&>(*this).extract(min_map, max_map, backend, stats);
}

void Map::commitPages() {
  if (!pager_) return;
  writeBack();
  pager_->commit(blocks_, revision_, metaOf(params_, scans_));
  pager_->flush();  // in the store when this returns
}

void Map::pageAfterScan(const Eigen::Vector3d& sensor_map) {
  using Clock = std::chrono::steady_clock;
  // The blocks a device backend created count against the budget before they have host
  // blocks: the device's changes are written back only when a commit or a paging round
  // needs the host map complete (every scan, that was most of the CUDA path's paging time).
  const size_t resident = blocks_.size() + backend_->cache().blocksNotInHostMap();
  // The kept records make way for the blocks a device backend made during the scan.
  (void)pager_->dropRecordsToFit(resident);
  pager_->noteResident(resident);
  pager_->noteSensor(sensor_map);  // for the room the next scan makes
  const bool due = pager_->commitDue(scans_);
  if (pager_->excessOverBudget(resident) == 0 && !due) return;
  auto t0 = Clock::now();
  {
    // The host map is made complete (the device's changes written back, and the blocks the
    // rays created on the device given host blocks) before it is committed or its clean
    // blocks are chosen.
    writeBack();
  }
  pager_->noteSyncSeconds(std::chrono::duration<double>(Clock::now() - t0).count());
  pager_->noteResident(blocks_.size());
  // Counted now: a block the device made but never applied gets no host block.
  // A round runs when the map is over its budget (a device backend's blocks) or when the
  // next scan, reaching as many new blocks as this one, would not fit: most rounds then run
  // here, between scans, rather than inside the next scan (Map::pageInKeys).
  const size_t next_scan = pager_->lastScanIncoming();
  // After the commit: its batch, on the writer until written, counts against the budget.
  if (due) pager_->commit(blocks_, revision_, metaOf(params_, scans_));
  const bool over = pager_->excessOverBudget(blocks_.size() + next_scan) > 0;
  if (!over) {
    (void)pager_->dropRecordsToFit(blocks_.size());  // room for the batch just submitted
    return;
  }
  t0 = Clock::now();
  // Blocks unchanged since the last commit leave first; when they cannot make the room, the
  // changed regions leave too, held as records for the next commit (Pager::pageOut): a
  // paging round writes nothing and commits nothing (the blocks near the sensor change with
  // every scan: committing them at every round wrote them many times over).
  std::vector<BlockIndex> out = pager_->victims(blocks_, sensor_map, /*clean_only=*/true);
  if (pager_->excessOverBudget(blocks_.size() - out.size() + next_scan) > 0)
    out = pager_->victims(blocks_, sensor_map, /*clean_only=*/false);
  {
    // Only the leaving blocks' device copies go; the cache keeps the rest.
    std::lock_guard<std::mutex> lock(*sync_mutex_);
    const auto t_evict = Clock::now();
    backend_->cache().forget(out, blocks_);
    pager_->stageCounters().seconds_evict += secondsSince(t_evict);
  }
  pager_->pageOut(out, blocks_);
  ++pager_->stageCounters().rounds_between_scans;
  (void)pager_->dropRecordsToFit(blocks_.size());
  releasePagedOutMemory();
  bumpViewEpoch();
  pager_->notePageOutSeconds(std::chrono::duration<double>(Clock::now() - t0).count());
}

void Map::releasePagedOutMemory() {
  pager_->store().releaseMappedPages();
  // A paging round leaves the arena with holes the size of the blocks that left, which the
  // next scans' blocks fill (new blocks take free slots first: the arena never outgrows its
  // peak). Its pages go back to the system, with the allocator's free memory, only when most
  // of the arena is free (the map shrank): at every round (W4) that cost page faults and TLB
  // shootdowns for the same peak.
  if (blocks_.freeSlots() * 2 <= blocks_.slots()) return;
  blocks_.releaseFreePages();
#ifdef __GLIBC__
  malloc_trim(0);
#endif
}

void Map::closePaging() noexcept {
  if (!pager_) return;
  try {
    commitPages();
  } catch (const std::exception& e) {
    logMessage(LogLevel::kWarning,
               std::string("paging: the last commit at close failed (the store keeps its "
                           "previous commit): ") +
                   e.what());
  }
  pager_.reset();
}

PagingStats Map::pagingStats() const {
  if (!pager_) return PagingStats();
  return pager_->stats(blocks_);
}

}  // namespace fragg
