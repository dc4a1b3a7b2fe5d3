#include "fragg_map/internal/pager.h"

#include <algorithm>
#include <array>
#include <cmath>
#include <cstring>
#include <string>
#include <tuple>

#include "fragg_map/errors.h"
#include "fragg_map/internal/byte_io.h"
#include "fragg_map/internal/seconds_since.h"
#include "fragg_map/log.h"

namespace fragg {

namespace {
constexpr char kStoreMetaMagic[8] = {'F', 'R', 'A', 'G', 'G', 'P', 'G', 'S'};
constexpr uint32_t kStoreMetaVersion = 1;
/// RAM one resident block takes in the host map (BlockMap): its cells; its metadata and state
/// masks twice (their arrays grow by doubling, and the buffers they leave behind, together up
/// to the array's size, stay with the allocator in a long-running process); its index slots at
/// the index's lowest load (a quarter: the table doubles at half full, and never shrinks),
/// twice for the same reason; and its entry in the coarse index's lists with their growth.
/// Checked against the process's resident memory per block by paging_memory_test (2,322-2,450
/// bytes measured).
constexpr size_t kResidentBlockBytes =
    sizeof(Block) + 2 * (sizeof(BlockMeta) + sizeof(BlockStateMasks)) +
    2 * 4 * (sizeof(BlockKey) + sizeof(BlockIndex)) + 4 * sizeof(BlockIndex);
/// The same in a host map whose per-block arrays were sized once for the budget's block count
/// (BlockMap::reserveSlots, Pager::reserveSlots): no array grows, so nothing is left behind:
/// its cells, metadata and state masks once, its index slots at the reserved index's lowest
/// load (a quarter) once, its entry in the coarse index's lists with their growth, and its
/// free-list entry. Checked by paging_memory_test.
constexpr size_t kReservedBlockBytes = sizeof(Block) + sizeof(BlockMeta) + sizeof(BlockStateMasks) +
                                       4 * (sizeof(BlockKey) + sizeof(BlockIndex)) +
                                       4 * sizeof(BlockIndex) + sizeof(BlockIndex);
/// RAM a kept record takes besides its bytes (its hash node and vector header).
constexpr size_t kKeptRecordOverhead = 64;

/// Regions in [slo, shi] (as a double: a box over the whole key range overflows 64 bits).
double regionCount(const BlockKey& slo, const BlockKey& shi) {
  return (double{1} + shi.x - slo.x) * (double{1} + shi.y - slo.y) * (double{1} + shi.z - slo.z);
}

/// The box of whole regions that holds [lo, hi]: blocks page in and out by region (a store
/// record holds a region), so a region is either resident or paged out as a whole.
void regionBox(BlockKey* lo, BlockKey* hi) {
  lo->x &= ~kRegionMask;
  lo->y &= ~kRegionMask;
  lo->z &= ~kRegionMask;
  hi->x |= kRegionMask;
  hi->y |= kRegionMask;
  hi->z |= kRegionMask;
}

}  // namespace

void PagingPolicy::validate() const {
  if (!std::isfinite(budget_mb) || budget_mb < 0)
    throw InvalidArgument("paging budget must be a finite number of MB >= 0");
  if (!std::isfinite(radius_m) || radius_m < 0)
    throw InvalidArgument("paging radius must be a finite distance >= 0");
  if (!(low_water > 0 && low_water <= 1))
    throw InvalidArgument("paging low_water must be in (0, 1]");
  if (!std::isfinite(commit_every_s) || commit_every_s < 0)
    throw InvalidArgument("paging commit interval must be a finite number of seconds >= 0");
}

std::vector<uint8_t> encodeStoreMeta(const StoreMapMeta& meta) {
  ByteWriter w;
  w.put(kStoreMetaMagic, sizeof(kStoreMetaMagic));
  w.put(kStoreMetaVersion);
  w.put(meta.resolution_m);
  const OccupancyParams& o = meta.occupancy;
  for (double v : {o.prob_hit, o.prob_miss, o.clamp_min, o.clamp_max, o.unknown_band}) w.put(v);
  w.put(static_cast<uint32_t>(kBlockSize));
  w.put(meta.scans);
  return w.bytes;
}

StoreMapMeta decodeStoreMeta(const std::vector<uint8_t>& bytes, const std::string& where) {
  ByteReader r(bytes, bytes.size(), where, "not a fragg_map page store");
  char magic[8];
  r.take(magic, sizeof(magic), "magic");
  if (std::memcmp(magic, kStoreMetaMagic, sizeof(magic)) != 0) r.fail("wrong metadata magic");
  const auto version = r.get<uint32_t>("version");
  if (version != kStoreMetaVersion) r.fail("unsupported version " + std::to_string(version));
  StoreMapMeta m;
  m.resolution_m = r.get<double>("resolution");
  OccupancyParams& o = m.occupancy;
  o.prob_hit = r.get<double>("prob_hit");
  o.prob_miss = r.get<double>("prob_miss");
  o.clamp_min = r.get<double>("clamp_min");
  o.clamp_max = r.get<double>("clamp_max");
  o.unknown_band = r.get<double>("unknown_band");
  if (r.get<uint32_t>("block edge") != static_cast<uint32_t>(kBlockSize))
    r.fail("block edge is not " + std::to_string(kBlockSize));
  m.scans = r.get<uint64_t>("scan count");
  if (r.remaining() != 0) r.fail("trailing bytes in the metadata");
  return m;
}

Pager::Pager(std::shared_ptr<PageStore> store, const PagingPolicy& policy, double resolution_m)
    : store_(std::move(store)),
      policy_(policy),
      block_m_(resolution_m * kBlockSize),
      block_bytes_(kResidentBlockBytes) {
  policy_.validate();
  for (const BlockKey& k : store_->keys()) addPagedOut(k);
  counters_.enabled = true;
  counters_.store = std::string(store_->kind()) + ":" + store_->path();
  if (policy_.background_writer) writer_ = std::make_unique<PageWriter>(store_);
}

Pager::~Pager() = default;  // the writer waits for its batch in flight

void Pager::addPagedOut(const BlockKey& key) {
  RegionBits& bits = paged_super_[superOf(key)];
  const size_t b = bitOf(key);
  if (bits.test(b)) return;
  bits.set(b);
  ++paged_count_;
}

void Pager::removePagedOut(const BlockKey& key) {
  auto it = paged_super_.find(superOf(key));
  if (it == paged_super_.end() || !it->second.test(bitOf(key))) return;
  it->second.reset(bitOf(key));
  --paged_count_;
  if (it->second.none()) paged_super_.erase(it);
  auto sat = saturated_super_.find(superOf(key));
  if (sat != saturated_super_.end()) {
    sat->second.reset(bitOf(key));
    if (sat->second.none()) saturated_super_.erase(sat);
  }
}

bool Pager::isPagedOutSaturated(const BlockKey& key) const {
  auto it = saturated_super_.find(superOf(key));
  return it != saturated_super_.end() && it->second.test(bitOf(key));
}

bool Pager::isPagedOut(const BlockKey& key) const {
  auto it = paged_super_.find(superOf(key));
  return it != paged_super_.end() && it->second.test(bitOf(key));
}

std::vector<BlockKey> Pager::pagedOutKeys() const {
  std::vector<BlockKey> out;
  out.reserve(paged_count_);
  for (const auto& [region, bits] : paged_super_)
    for (size_t b = bits._Find_first(); b < bits.size(); b = bits._Find_next(b))
      out.push_back(keyOfBit(region, b));
  return out;
}

template <class Fn>
void Pager::forEachPagedOutIn(const BlockKey& lo, const BlockKey& hi, Fn&& fn) const {
  if (paged_count_ == 0) return;
  const BlockKey slo = superOf(lo), shi = superOf(hi);
  auto visit = [&](const BlockKey& region, const RegionBits& bits) {
    for (size_t b = bits._Find_first(); b < bits.size(); b = bits._Find_next(b)) {
      const BlockKey k = keyOfBit(region, b);
      if (k.x >= lo.x && k.x <= hi.x && k.y >= lo.y && k.y <= hi.y && k.z >= lo.z && k.z <= hi.z)
        if (!fn(k)) return false;
    }
    return true;
  };
  if (regionCount(slo, shi) > static_cast<double>(paged_super_.size())) {
    for (const auto& [region, bits] : paged_super_)
      if (!visit(region, bits)) return;
    return;
  }
  for (int32_t z = slo.z; z <= shi.z; ++z)
    for (int32_t y = slo.y; y <= shi.y; ++y)
      for (int32_t x = slo.x; x <= shi.x; ++x) {
        auto it = paged_super_.find({x, y, z});
        if (it != paged_super_.end() && !visit(it->first, it->second)) return;
      }
}

bool Pager::anyPagedOut(BlockKey lo, BlockKey hi) const {
  regionBox(&lo, &hi);
  bool any = false;
  forEachPagedOutIn(lo, hi, [&](const BlockKey&) {
    any = true;
    return false;  // one is enough
  });
  return any;
}

std::vector<BlockKey> Pager::pagedOutRegionsIn(const BlockKey& lo, const BlockKey& hi) const {
  std::vector<BlockKey> regions;
  if (paged_count_ == 0) return regions;
  // Asked before every ray pass of a device scan, over its whole window: a paged-out bitset
  // (kBlockBits coarser than a block) is tested a region at a time against the region's
  // mask, not a bit at a time.
  static_assert(kRegionBits <= kBlockBits, "a region lies within one paged-out bitset");
  constexpr int kSub = 1 << (kBlockBits - kRegionBits);  // regions per bitset edge
  static const std::vector<RegionBits> masks = [] {
    std::vector<RegionBits> m(size_t{kSub} * kSub * kSub);
    constexpr int32_t n = 1 << kBlockBits;
    for (int32_t z = 0; z < n; ++z)
      for (int32_t y = 0; y < n; ++y)
        for (int32_t x = 0; x < n; ++x) {
          const BlockKey b{x, y, z};
          const BlockKey r = regionOf(b);
          m[size_t((r.z * kSub + r.y) * kSub + r.x)].set(bitOf(b));
        }
    return m;
  }();
  const BlockKey rlo = regionOf(lo), rhi = regionOf(hi);
  auto visit = [&](const BlockKey& super, const RegionBits& bits) {
    for (int32_t z = 0; z < kSub; ++z)
      for (int32_t y = 0; y < kSub; ++y)
        for (int32_t x = 0; x < kSub; ++x) {
          const BlockKey r{super.x * kSub + x, super.y * kSub + y, super.z * kSub + z};
          if (r.x < rlo.x || r.x > rhi.x || r.y < rlo.y || r.y > rhi.y || r.z < rlo.z ||
              r.z > rhi.z)
            continue;
          if ((bits & masks[size_t((z * kSub + y) * kSub + x)]).any()) regions.push_back(r);
        }
  };
  const BlockKey slo = superOf(lo), shi = superOf(hi);
  if (regionCount(slo, shi) > static_cast<double>(paged_super_.size())) {
    for (const auto& [super, bits] : paged_super_)
      if (super.x >= slo.x && super.x <= shi.x && super.y >= slo.y && super.y <= shi.y &&
          super.z >= slo.z && super.z <= shi.z)
        visit(super, bits);
  } else {
    for (int32_t z = slo.z; z <= shi.z; ++z)
      for (int32_t y = slo.y; y <= shi.y; ++y)
        for (int32_t x = slo.x; x <= shi.x; ++x) {
          auto it = paged_super_.find({x, y, z});
          if (it != paged_super_.end()) visit(it->first, it->second);
        }
  }
  std::sort(regions.begin(), regions.end(), storeOrder);
  return regions;
}

bool Pager::readPagedOut(const BlockKey& key, Block* out) {
  auto held = held_.find(regionOf(key));
  if (held != held_.end()) return store_->decode(held->second.record, key, out);
  if (writer_) {
    const PageWriter::Pending p = writer_->findPending(key, out);
    if (p != PageWriter::Pending::kNone) return p == PageWriter::Pending::kFound;
  }
  return store_->read(key, out);
}

std::vector<BlockIndex> Pager::pageIn(BlockKey lo, BlockKey hi, BlockMap& blocks) {
  if (paged_count_ == 0) return {};
  regionBox(&lo, &hi);
  std::vector<BlockKey> wanted;
  forEachPagedOutIn(lo, hi, [&](const BlockKey& k) {
    wanted.push_back(k);
    return true;
  });
  return readBack(std::move(wanted), blocks);
}

std::vector<BlockIndex> Pager::pageIn(const std::vector<BlockKey>& keys, BlockMap& blocks) {
  if (paged_count_ == 0) return {};
  return readBack(pagedOutOfRegions(keys, blocks, nullptr), blocks);
}

std::vector<BlockKey> Pager::pagedOutOfRegions(const std::vector<BlockKey>& keys,
                                               const BlockMap& blocks, size_t* fresh) const {
  // Both passes read only (the index and the paged-out bits): the keys are split over the
  // threads (a LiDAR scan reaches tens of thousands of blocks; this ran on the map's thread).
  const long n = static_cast<long>(keys.size());
  if (fresh) {
    size_t count = 0;
#pragma omp parallel for schedule(static) reduction(+ : count) if (n > 4096)
    for (long j = 0; j < n; ++j) count += !isPagedOut(keys[j]) && blocks.find(keys[j]) == kNoBlock;
    *fresh = count;
  }
  if (paged_count_ == 0) return {};
  // Every paged-out block of the keys' regions (a region comes back whole).
  std::vector<uint8_t> reaches(keys.size());
#pragma omp parallel for schedule(static) if (n > 4096)
  for (long j = 0; j < n; ++j) reaches[j] = regionHasPagedOut(keys[j]);
  std::vector<BlockKey> regions;
  for (long j = 0; j < n; ++j)
    if (reaches[j]) regions.push_back(regionOf(keys[j]));
  std::sort(regions.begin(), regions.end(), storeOrder);
  regions.erase(std::unique(regions.begin(), regions.end()), regions.end());
  std::vector<BlockKey> wanted;
  for (const BlockKey& r : regions) {
    BlockKey lo = firstBlockOf(r), hi = lo;
    regionBox(&lo, &hi);
    forEachPagedOutIn(lo, hi, [&](const BlockKey& k) {
      wanted.push_back(k);
      return true;
    });
  }
  return wanted;
}

bool Pager::regionHasPagedOut(const BlockKey& key) const {
  const auto it = paged_super_.find(superOf(key));
  if (it == paged_super_.end()) return false;
  // A region lies inside one 8x8x8-block super region (kRegionBits <= kBlockBits): its bits
  // there, one mask for each of the region's places in it.
  constexpr int kPlacesBits = kBlockBits - kRegionBits;
  static const std::array<RegionBits, size_t{1} << (3 * kPlacesBits)> masks = [] {
    std::array<RegionBits, size_t{1} << (3 * kPlacesBits)> out{};
    for (size_t bit = 0; bit < RegionBits().size(); ++bit) {
      const BlockKey b = keyOfBit(BlockKey{0, 0, 0}, bit);
      out[placeOf(b)].set(bit);
    }
    return out;
  }();
  return (it->second & masks[placeOf(key)]).any();
}

std::vector<BlockIndex> Pager::readBack(std::vector<BlockKey> wanted, BlockMap& blocks) {
  if (wanted.empty()) return {};
  const auto t0 = Clock::now();
  // Key order: the stores keep records sorted, so neighbouring reads share pages.
  std::sort(wanted.begin(), wanted.end(), [](const BlockKey& a, const BlockKey& b) {
    return std::tie(a.z, a.y, a.x) < std::tie(b.z, b.y, b.x);
  });
  blocks.reserve(wanted.size());
  std::vector<BlockIndex> read;
  read.reserve(wanted.size());
  std::vector<std::pair<BlockKey, BlockRecord>> records;
  // On any failure the blocks made here go again: they stay paged out, the map is as before.
  auto undo = [&] {
    for (size_t j = 0; j < read.size(); ++j) blocks.erase(wanted[j]);
  };
  for (const BlockKey& k : wanted) {
    bool created = false;
    const BlockIndex i = blocks.findOrCreate(k, &created, /*initialise=*/false);
    if (!created) {
      undo();
      throw IoError("paging: block paged out and resident at once (internal error)");
    }
    read.push_back(i);
  }
  try {
    // A commit not yet written holds newer records than the store: those first, the rest
    // from one snapshot of the store.
    std::vector<BlockKey> from_store;
    std::vector<Block*> outs;
    for (size_t j = 0; j < wanted.size(); ++j) {
      Block* out = &blocks.block(read[j]);
      auto held = held_.find(regionOf(wanted[j]));
      if (held != held_.end()) {
        if (!store_->decode(held->second.record, wanted[j], out))
          throw IoError(store_->path() + ": block missing from its region's held record");
        continue;
      }
      if (writer_) {
        const PageWriter::Pending p = writer_->findPending(wanted[j], out);
        if (p == PageWriter::Pending::kMissing)
          throw IoError(store_->path() + ": block missing from its region's pending record");
        if (p == PageWriter::Pending::kFound) {
          ++counters_.pages_read_pending;
          continue;
        }
      }
      from_store.push_back(wanted[j]);
      outs.push_back(out);
    }
    const std::vector<bool> found = store_->readMany(from_store, outs, &records);
    for (bool f : found)
      if (!f) throw IoError(store_->path() + ": block record missing from the page store");
  } catch (...) {
    undo();
    throw;
  }
  // The records read are the regions' last (a region comes back whole): kept, so that the
  // next commit compresses only the blocks that change. Regions read from a pending batch
  // have none kept (their next commit compresses them whole).
  for (auto& [region, record] : records) keepRecord(region, std::move(record), blocks.size());
  // Regions read from their held record: it becomes their kept record, and they are written
  // at the next commit (the store's record is older).
  for (const BlockKey& k : wanted) {
    auto held = held_.find(regionOf(k));
    if (held == held_.end()) continue;
    const BlockKey region = held->first;
    BlockRecord record = std::move(held->second.record);
    held_bytes_ -= record.capacity() + kKeptRecordOverhead;
    held_.erase(held);
    stale_.emplace(region, true);
    keepRecord(region, std::move(record), blocks.size());
  }
  for (size_t j = 0; j < wanted.size(); ++j) {
    BlockMeta& m = blocks.meta(read[j]);
    m.changed_at = m.occupied_at = m.state_at = 0;  // clean: equal to its record
    // Saturated when it left and unchanged since: the rays' misses may skip it again.
    m.free_saturated_at = isPagedOutSaturated(wanted[j]) ? m.changed_at : BlockMeta::kNotSaturated;
    removePagedOut(wanted[j]);
  }
  counters_.pages_read += wanted.size();
  noteResident(blocks.size());
  counters_.seconds_page_in += secondsSince(t0);
  return read;
}

std::vector<BlockIndex> Pager::pageInAll(BlockMap& blocks) {
  if (paged_count_ == 0) return {};
  const int32_t lim = 0x7fffffff >> kBlockBits;
  return pageIn({-lim - 1, -lim - 1, -lim - 1}, {lim, lim, lim}, blocks);
}

void Pager::touch(const BlockKey& lo, const BlockKey& hi, uint64_t stamp) {
  const BlockKey slo = superOf(lo), shi = superOf(hi);
  const double volume = regionCount(slo, shi);
  if (volume > 4194304.0) return;  // a box this large is not a sensor's or a query's
  for (int32_t z = slo.z; z <= shi.z; ++z)
    for (int32_t y = slo.y; y <= shi.y; ++y)
      for (int32_t x = slo.x; x <= shi.x; ++x) last_used_[{x, y, z}] = stamp;
}

void Pager::forgetAll(const BlockMap& blocks) {
  for (const BlockKey& k : pagedOutKeys()) erased_.push_back(k);
  blocks.forEach([&](BlockIndex i) { erased_.push_back(blocks.meta(i).key); });
  paged_super_.clear();
  saturated_super_.clear();
  paged_count_ = 0;
  last_used_.clear();
  records_.clear();
  record_bytes_ = 0;
  held_.clear();
  held_bytes_ = 0;
  stale_.clear();
}

void Pager::keepRecord(const BlockKey& region, BlockRecord record, size_t resident) {
  dropRecord(region);
  record.shrink_to_fit();
  const size_t bytes = record.capacity() + kKeptRecordOverhead;
  // Kept records are a saving, never a reason to page blocks out: one that does not fit the
  // budget is not kept (its region is compressed whole at its next commit).
  if (policy_.budget_mb > 0 && countedBytes(resident + reserved_blocks_) + bytes > budgetBytes())
    return;
  records_.emplace(region, std::move(record));
  record_bytes_ += bytes;
}

bool Pager::dropRecordsToFit(size_t resident) {
  if (policy_.budget_mb <= 0) return true;
  if (resident * block_bytes_ > budgetBytes()) return false;
  if (countedBytes(resident) <= budgetBytes()) return true;
  // Kept records go first (a dropped record costs its region's changed blocks compressed
  // whole at their next commit); the commit in flight is waited for only when they are not
  // enough: waiting stalls the map's thread for the rest of the writer's transaction.
  std::vector<BlockKey> regions;
  regions.reserve(records_.size());
  for (const auto& r : records_) regions.push_back(r.first);
  std::sort(regions.begin(), regions.end(), storeOrder);  // deterministic
  for (const BlockKey& r : regions) {
    if (countedBytes(resident) <= budgetBytes()) break;
    dropRecord(r);
  }
  if (countedBytes(resident) > budgetBytes() && writerBytes() > 0) {
    try {
      flush();  // its records leave RAM once written
    } catch (const IoError&) {
      // The failed batch stays in RAM (counted) and goes with the next commit.
    }
  }
  return true;
}

void Pager::dropRecord(const BlockKey& region) {
  auto it = records_.find(region);
  if (it == records_.end()) return;
  record_bytes_ -= it->second.capacity() + kKeptRecordOverhead;
  records_.erase(it);
}

bool Pager::commitDue(uint64_t scans) const {
  if (policy_.commit_every_scans > 0 && scans >= committed_scans_ + policy_.commit_every_scans)
    return true;
  if (policy_.budget_mb > 0 && held_bytes_ > budgetBytes() / 8) return true;
  return policy_.commit_every_s > 0 && secondsSince(last_commit_) >= policy_.commit_every_s;
}

size_t Pager::budgetBytes() const {
  return static_cast<size_t>(policy_.budget_mb * 1024.0 * 1024.0);
}

size_t Pager::residentBlockBytes() { return kResidentBlockBytes; }

size_t Pager::reservedBlockBytes() { return kReservedBlockBytes; }

size_t Pager::reserveSlots(BlockMap& blocks) {
  if (policy_.budget_mb <= 0) return 0;
  const size_t wanted = budgetBytes() / kReservedBlockBytes;
  const size_t reserved = blocks.reserveSlots(wanted);
  // The arrays hold the budget's blocks without growing: a block costs the reserved figure.
  // (A map already larger than its arrays' reservation keeps the growth figure.)
  if (reserved >= wanted && blocks.slots() <= wanted) block_bytes_ = kReservedBlockBytes;
  return reserved;
}

size_t Pager::budgetBlocks() const { return budgetBytes() / block_bytes_; }

size_t Pager::writerBytes() const {
  if (!writer_) return 0;
  const size_t pending = writer_->pendingBytes();
  return pending + (pending > 0 ? store_->commitMemoryBytes(pending) : 0);
}

size_t Pager::countedBytes(size_t resident) const {
  return resident * block_bytes_ + record_bytes_ + held_bytes_ + writerBytes();
}

size_t Pager::blocksWithin(double fraction) const {
  // Kept records are a saving, never a reason to page a block out: they fill the room the
  // blocks leave and are dropped when blocks need it (dropRecordsToFit). The held records and
  // the commit in flight stay whatever leaves.
  const double room = fraction * static_cast<double>(budgetBytes()) -
                      static_cast<double>(held_bytes_ + writerBytes());
  return room <= 0 ? 0 : static_cast<size_t>(room / static_cast<double>(block_bytes_));
}

bool Pager::overBudget(const BlockMap& blocks) const { return excessOverBudget(blocks.size()) > 0; }

size_t Pager::excessOverBudget(size_t resident) const {
  if (policy_.budget_mb <= 0) return 0;
  // Without the kept records: they are dropped to fit (dropRecordsToFit) before any block leaves.
  if (resident * block_bytes_ + held_bytes_ + writerBytes() <= budgetBytes()) return 0;
  const size_t within = blocksWithin(1.0);
  return resident > within ? resident - within : 1;
}

size_t Pager::roomFor(size_t resident) const {
  if (policy_.budget_mb <= 0) return SIZE_MAX;
  const size_t within = blocksWithin(1.0);
  return within > resident ? within - resident : 0;
}

void Pager::flush() {
  if (writer_) writer_->wait();
}

void Pager::commit(const BlockMap& blocks, uint64_t revision, const StoreMapMeta& meta) {
  const auto t0 = Clock::now();
  // The regions to write: those of the dirty blocks and of the blocks erased since the last
  // commit. A region is resident or paged out as a whole: its record is its resident blocks.
  std::unordered_map<BlockKey, size_t, BlockKeyHash> slot;
  std::vector<BlockKey> regions;
  auto addRegion = [&](const BlockKey& region) {
    if (slot.emplace(region, regions.size()).second) regions.push_back(region);
  };
  blocks.forEach([&](BlockIndex i) {
    const BlockMeta& m = blocks.meta(i);
    if (dirty(m)) addRegion(regionOf(m.key));
  });
  for (const BlockKey& k : erased_) addRegion(regionOf(k));
  for (const auto& s : stale_) addRegion(s.first);
  // A region's last record (when kept) gives its clean blocks' encodings: only the blocks
  // changed since are compressed (given with their cells; the others as nullptr).
  std::vector<const BlockRecord*> previous(regions.size(), nullptr);
  for (size_t j = 0; j < regions.size(); ++j) {
    auto it = records_.find(regions[j]);
    if (it != records_.end()) previous[j] = &it->second;
  }
  std::vector<RegionBlocks> members(regions.size());
  size_t compressed = 0;
  if (!regions.empty())
    blocks.forEach([&](BlockIndex i) {
      const BlockMeta& m = blocks.meta(i);
      auto it = slot.find(regionOf(m.key));
      if (it == slot.end()) return;
      const bool encode = !previous[it->second] || dirty(m);
      compressed += encode;
      members[it->second].emplace_back(m.key, encode ? &blocks.block(i) : nullptr);
    });
  std::vector<size_t> order(regions.size());
  for (size_t j = 0; j < order.size(); ++j) order[j] = j;
  std::sort(order.begin(), order.end(),
            [&](size_t a, size_t b) { return storeOrder(regions[a], regions[b]); });
  PageWriter::Batch batch;
  std::vector<RegionBlocks> to_encode;
  std::vector<BlockKey> to_encode_keys;
  std::vector<const BlockRecord*> to_encode_previous;
  size_t block_count = 0;
  for (size_t j : order) {
    if (members[j].empty()) {
      // Every block of the region erased: its record goes (a region with a block paged out
      // has no resident blocks erased: it left whole, clean).
      BlockKey lo = firstBlockOf(regions[j]), hi = lo;
      regionBox(&lo, &hi);
      bool paged = false;
      forEachPagedOutIn(lo, hi, [&](const BlockKey&) { return !(paged = true); });
      if (!paged) batch.erases.push_back(regions[j]);
      continue;
    }
    block_count += members[j].size();
    to_encode.push_back(std::move(members[j]));
    to_encode_keys.push_back(regions[j]);
    to_encode_previous.push_back(previous[j]);
  }
  // The records are the commit's snapshot: encoded here, on every core.
  std::vector<BlockRecord> records = store_->encode(to_encode, to_encode_previous);
  for (const BlockKey& r : batch.erases) dropRecord(r);
  batch.puts.reserve(records.size() + held_.size());
  for (size_t j = 0; j < records.size(); ++j) {
    // A copy: the batch's goes to the writer.
    keepRecord(to_encode_keys[j], records[j], blocks.size());
    batch.puts.emplace_back(to_encode_keys[j], std::move(records[j]));
  }
  // The records of the changed regions that left since the last commit (paged out: none of
  // them is among the resident regions above).
  for (auto& [region, held] : held_) {
    block_count += held.blocks;
    batch.puts.emplace_back(region, std::move(held.record));
  }
  held_.clear();
  held_bytes_ = 0;
  stale_.clear();
  std::sort(batch.puts.begin(), batch.puts.end(),
            [](const auto& a, const auto& b) { return storeOrder(a.first, b.first); });
  batch.meta = encodeStoreMeta(meta);
  const size_t record_count = batch.puts.size();
  if (writer_)
    writer_->submit(std::move(batch));  // waits for the previous commit first
  else
    store_->commitRecords(batch.puts, batch.erases, batch.meta);
  erased_.clear();
  all_dirty_ = false;
  committed_revision_ = revision;
  committed_scans_ = meta.scans;
  last_commit_ = Clock::now();
  counters_.pages_written += block_count;
  counters_.blocks_encoded += compressed;
  counters_.records_written += record_count;
  ++counters_.commits;
  counters_.committed_scans = meta.scans;
  counters_.seconds_commit += secondsSince(t0);
}

std::vector<BlockIndex> Pager::victims(const BlockMap& blocks, const Eigen::Vector3d& sensor_m,
                                       bool clean_only, size_t incoming,
                                       const std::vector<BlockKey>* pinned) {
  last_sensor_m_ = sensor_m;
  const size_t target = blocksWithin(policy_.low_water);
  if (blocks.size() + incoming <= target) return {};
  const auto t0 = Clock::now();
  std::unordered_map<BlockKey, bool, BlockKeyHash> pinned_regions;
  if (pinned)
    for (const BlockKey& k : *pinned) pinned_regions.emplace(regionOf(k), true);
  // Blocks leave by region (a store record holds a region): the candidates are the resident
  // regions, each with its blocks. A region lies inside one cell of the map's coarse index
  // (kBlockSize^3 blocks), so the blocks are grouped cell by cell into the cell's regions: no
  // look-up per block (this pass over every resident block runs at every paging round).
  static_assert(kRegionBits <= kBlockBits, "a region lies inside a coarse index cell");
  constexpr int kRegionsPerAxis = 1 << (kBlockBits - kRegionBits);
  constexpr int kRegionsPerCell = kRegionsPerAxis * kRegionsPerAxis * kRegionsPerAxis;
  struct Candidate {
    bool near = false;   ///< within the radius: after every other region
    uint64_t order = 0;  ///< outside: the last use; inside: farther first
    BlockKey region;
    bool dirty = false;
    uint32_t first = 0, count = 0;  ///< its blocks: members[first, first + count)
  };
  std::vector<Candidate> candidates;
  std::vector<BlockIndex> members;
  members.reserve(blocks.size());
  blocks.forEachCoarseCell([&](const std::vector<BlockIndex>& cell) {
    const auto local = [&](BlockIndex i) {
      const BlockKey r = regionOf(blocks.meta(i).key);
      return ((r.z & (kRegionsPerAxis - 1)) * kRegionsPerAxis + (r.y & (kRegionsPerAxis - 1))) *
                 kRegionsPerAxis +
             (r.x & (kRegionsPerAxis - 1));
    };
    std::array<uint32_t, kRegionsPerCell> count{}, at{};
    std::array<int32_t, kRegionsPerCell> candidate;
    candidate.fill(-1);
    for (const BlockIndex i : cell) ++count[local(i)];
    uint32_t filled = static_cast<uint32_t>(members.size());
    for (int r = 0; r < kRegionsPerCell; ++r) {
      at[r] = filled;
      filled += count[r];
    }
    members.resize(filled);
    for (const BlockIndex i : cell) {
      const int r = local(i);
      const BlockMeta& m = blocks.meta(i);
      if (candidate[r] < 0) {
        candidate[r] = static_cast<int32_t>(candidates.size());
        candidates.emplace_back();
        candidates.back().region = regionOf(m.key);
        candidates.back().first = at[r];
      }
      Candidate& c = candidates[candidate[r]];
      c.dirty |= dirty(m);
      members[at[r] + c.count++] = i;
    }
  });
  // A region with a block erased since the last commit has a record older than it.
  if (!erased_.empty() || !stale_.empty()) {
    std::unordered_map<BlockKey, size_t, BlockKeyHash> slot;
    slot.reserve(candidates.size());
    for (size_t j = 0; j < candidates.size(); ++j) slot.emplace(candidates[j].region, j);
    for (const BlockKey& k : erased_) {
      auto it = slot.find(regionOf(k));
      if (it != slot.end()) candidates[it->second].dirty = true;
    }
    for (const auto& s : stale_) {
      auto it = slot.find(s.first);
      if (it != slot.end()) candidates[it->second].dirty = true;
    }
  }
  const double r2 = policy_.radius_m * policy_.radius_m;
  const double region_m = block_m_ * (1 << kRegionBits);
  std::vector<Candidate*> order;
  order.reserve(candidates.size());
  for (Candidate& c : candidates) {
    if (clean_only && c.dirty) continue;
    const BlockKey& r = c.region;
    if (pinned_regions.count(r)) continue;  // the scan in progress holds its blocks
    const Eigen::Vector3d centre =
        (Eigen::Vector3d(r.x, r.y, r.z).array() + 0.5).matrix() * region_m;
    const double d2 = (centre - sensor_m).squaredNorm();
    if (d2 <= r2) {
      if (clean_only) continue;  // near regions leave only in a full round (after a commit)
      // Millimetres from the radius inwards: the farthest near region goes first.
      c.near = true;
      c.order = static_cast<uint64_t>((r2 - d2) * 1e3);
    } else {
      auto it = last_used_.find(superOf(firstBlockOf(r)));
      c.order = it == last_used_.end() ? 0 : it->second;
    }
    order.push_back(&c);
  }
  std::sort(order.begin(), order.end(), [](const Candidate* a, const Candidate* b) {
    return std::tie(a->near, a->order, a->region.z, a->region.y, a->region.x) <
           std::tie(b->near, b->order, b->region.z, b->region.y, b->region.x);
  });
  const size_t needed = blocks.size() + incoming - target;
  std::vector<BlockIndex> out;
  out.reserve(needed + kBlocksPerRegion);
  bool any_near = false;
  for (const Candidate* c : order) {
    if (out.size() >= needed) break;
    out.insert(out.end(), members.begin() + c->first, members.begin() + c->first + c->count);
    any_near |= c->near;
  }
  counters_.seconds_choose += secondsSince(t0);
  if (any_near && !radius_yield_warned_) {
    radius_yield_warned_ = true;
    logMessage(LogLevel::kWarning,
               "paging: the blocks within the paging radius (" + std::to_string(policy_.radius_m) +
                   " m) exceed the RAM budget (" + std::to_string(policy_.budget_mb) +
                   " MB): the budget wins, the farthest of them are paged out");
  }
  return out;
}

void Pager::pageOut(const std::vector<BlockIndex>& victims, BlockMap& blocks) {
  std::vector<BlockKey> keys;
  keys.reserve(victims.size());
  // The regions with a change the store lacks (a dirty block, an erased one, or read back
  // from a held record) leave as records held for the next commit.
  std::unordered_map<BlockKey, bool, BlockKeyHash> changed;
  for (const BlockKey& k : erased_) changed.emplace(regionOf(k), true);
  std::unordered_map<BlockKey, size_t, BlockKeyHash> slot;
  std::vector<BlockKey> held_regions;
  std::vector<RegionBlocks> members;
  std::vector<const BlockRecord*> previous;
  std::vector<char> region_dirty;
  for (BlockIndex i : victims) {
    const BlockMeta& m = blocks.meta(i);
    keys.push_back(m.key);
    const BlockKey region = regionOf(m.key);
    auto it = slot.find(region);
    if (it == slot.end()) {
      it = slot.emplace(region, held_regions.size()).first;
      held_regions.push_back(region);
      auto kept = records_.find(region);
      previous.push_back(kept == records_.end() ? nullptr : &kept->second);
      members.emplace_back();
      region_dirty.push_back(0);
    }
    region_dirty[it->second] |= dirty(m);
    const bool encode = !previous[it->second] || dirty(m);
    members[it->second].emplace_back(m.key, encode ? &blocks.block(i) : nullptr);
  }
  std::vector<RegionBlocks> to_encode;
  std::vector<const BlockRecord*> to_encode_previous;
  std::vector<BlockKey> to_encode_keys;
  for (size_t j = 0; j < held_regions.size(); ++j) {
    if (!region_dirty[j] && !changed.count(held_regions[j]) && !stale_.count(held_regions[j]))
      continue;  // clean: the store (or the writer's batch) has its record
    for (const auto& [k, b] : members[j]) counters_.blocks_encoded += b != nullptr;
    to_encode.push_back(std::move(members[j]));
    to_encode_previous.push_back(previous[j]);
    to_encode_keys.push_back(held_regions[j]);
  }
  if (!to_encode.empty()) {
    const auto t_encode = Clock::now();
    std::vector<BlockRecord> records = store_->encode(to_encode, to_encode_previous);
    counters_.seconds_encode += secondsSince(t_encode);
    for (size_t j = 0; j < records.size(); ++j) {
      Held& h = held_[to_encode_keys[j]];
      held_bytes_ -= h.record.empty() ? 0 : h.record.capacity() + kKeptRecordOverhead;
      h.record = std::move(records[j]);
      h.record.shrink_to_fit();
      h.blocks = to_encode[j].size();
      held_bytes_ += h.record.capacity() + kKeptRecordOverhead;
      stale_.erase(to_encode_keys[j]);
      counters_.blocks_held += h.blocks;
    }
  }
  for (size_t j = 0; j < keys.size(); ++j) {
    dropRecord(regionOf(keys[j]));  // the region leaves whole: its record is stored or held
    addPagedOut(keys[j]);
    if (blocks.meta(victims[j]).freeSaturated())
      saturated_super_[superOf(keys[j])].set(bitOf(keys[j]));
  }
  blocks.erase(keys);
  blocks.orderFreeSlots();
  counters_.pages_evicted += keys.size();
}

void Pager::noteResident(size_t resident) {
  counters_.peak_resident_blocks = std::max<uint64_t>(counters_.peak_resident_blocks, resident);
  counters_.peak_counted_bytes =
      std::max<uint64_t>(counters_.peak_counted_bytes, countedBytes(resident));
}

PagingStats Pager::stats(const BlockMap& blocks) const {
  PagingStats s = counters_;
  s.resident_blocks = blocks.size();
  s.peak_resident_blocks = std::max<uint64_t>(s.peak_resident_blocks, blocks.size());
  s.paged_blocks = paged_count_;
  s.budget_blocks = policy_.budget_mb > 0 ? budgetBlocks() : 0;
  s.budget_bytes = policy_.budget_mb > 0 ? budgetBytes() : 0;
  s.peak_counted_bytes = std::max<uint64_t>(s.peak_counted_bytes, countedBytes(blocks.size()));
  s.record_cache_bytes = record_bytes_;
  s.store_bytes = store_->diskBytes();
  if (writer_) s.seconds_writer = writer_->secondsWriting();
  return s;
}

}  // namespace fragg
