#include "fragg_map/block_map.h"

#include <sys/mman.h>

#include <algorithm>
#include <cstdlib>
#include <functional>
#include <new>
#include <tuple>

namespace fragg {

namespace {
class PlainChunkAllocator : public ChunkAllocator {
 public:
  void* allocate(size_t bytes) override {
    void* p = std::aligned_alloc(4096, (bytes + 4095) / 4096 * 4096);
    if (!p) throw std::bad_alloc();
    return p;
  }
  void deallocate(void* p, size_t) override { std::free(p); }
  const char* name() const override { return "plain"; }
  bool pagesReleasable() const override { return true; }
};

constexpr size_t kPageBytes = 4096;
static_assert(kPageBytes % sizeof(Block) == 0, "a memory page holds whole blocks");
static_assert(BlockMap::kBlocksPerChunk * sizeof(Block) % kPageBytes == 0,
              "a chunk holds whole memory pages");
constexpr size_t kBlocksPerPage = kPageBytes / sizeof(Block);
/// The shortest run of free pages releaseFreePages hands back (64 KiB).
constexpr size_t kMinReleasePages = 16;

void initBlock(Block& b) {
  for (Cell& c : b.cells) c = Cell();
}
}  // namespace

std::shared_ptr<ChunkAllocator> plainChunkAllocator() {
  static auto allocator = std::make_shared<PlainChunkAllocator>();
  return allocator;
}

BlockMap::BlockMap(std::shared_ptr<ChunkAllocator> allocator) : allocator_(std::move(allocator)) {}

BlockMap::~BlockMap() {
  for (Block* c : chunks_) allocator_->deallocate(c, kBlocksPerChunk * sizeof(Block));
}

BlockMap::BlockMap(BlockMap&& o) noexcept { *this = std::move(o); }

BlockMap& BlockMap::operator=(BlockMap&& o) noexcept {
  if (this == &o) return *this;
  for (Block* c : chunks_) allocator_->deallocate(c, kBlocksPerChunk * sizeof(Block));
  allocator_ = std::move(o.allocator_);
  chunks_ = std::move(o.chunks_);
  meta_ = std::move(o.meta_);
  masks_ = std::move(o.masks_);
  changes_ = std::move(o.changes_);
  free_ = std::move(o.free_);
  free_sorted_ = o.free_sorted_;
  page_released_ = std::move(o.page_released_);
  index_ = std::move(o.index_);
  super_ = std::move(o.super_);
  o.allocator_ = allocator_;
  o.chunks_.clear();
  o.clear();
  return *this;
}

static_assert(kNoBlock == BlockKeyTable::kNone, "the index's empty value is kNoBlock");

BlockIndex BlockMap::find(const BlockKey& key) const { return index_.find(key); }

const Block* BlockMap::findBlock(const BlockKey& key) const {
  const BlockIndex i = find(key);
  return i == kNoBlock ? nullptr : &block(i);
}

Block* BlockMap::findBlock(const BlockKey& key) {
  const BlockIndex i = find(key);
  return i == kNoBlock ? nullptr : &block(i);
}

const Cell* BlockMap::findCell(const VoxelKey& key) const {
  const Block* b = findBlock(blockKeyOf(key));
  return b ? &b->cells[cellIndexOf(key)] : nullptr;
}

BlockIndex BlockMap::findOrCreate(const BlockKey& key, bool* created, bool initialise) {
  const BlockIndex found = index_.find(key);
  if (created) *created = found == kNoBlock;
  if (found != kNoBlock) return found;
  index_.reserve(index_.size() + 1);  // may throw: before anything changes
  const bool reused = !free_.empty();
  BlockIndex i;
  if (reused) {
    i = free_.back();
  } else {
    i = static_cast<BlockIndex>(meta_.size());
    if (i % kBlocksPerChunk == 0)
      chunks_.push_back(static_cast<Block*>(allocator_->allocate(kBlocksPerChunk * sizeof(Block))));
    masks_.emplace_back();  // first: a throw leaves masks_ longer than meta_, never shorter
    meta_.emplace_back();
  }
  try {
    super_[superKeyOf(key)].push_back(i);
  } catch (...) {
    if (!reused) free_.push_back(i);  // the new slot stays for the next block
    throw;
  }
  if (reused) {
    free_.pop_back();
    free_sorted_ = std::min(free_sorted_, free_.size());
    if (i / kBlocksPerPage < page_released_.size()) page_released_[i / kBlocksPerPage] = 0;
  }
  index_.insert(key, i);
  if (initialise) initBlock(block(i));
  BlockMeta& m = meta_[i];
  m = BlockMeta();
  m.key = key;
  masks_[i] = BlockStateMasks();
  return i;
}

size_t BlockMap::reserveSlots(size_t n) {
  // masks_ first: a throw leaves the arrays as they were or masks_ larger, never meta_ alone.
  masks_.reserve(n);
  meta_.reserve(n);
  free_.reserve(n);
  index_.reserve(n);
  return std::min(meta_.capacity(), masks_.capacity());
}

void BlockMap::erase(const BlockKey& key) {
  const BlockIndex i = index_.find(key);
  if (i == kNoBlock) return;
  index_.erase(key);
  auto sit = super_.find(superKeyOf(key));
  if (sit != super_.end()) {
    auto& v = sit->second;
    v.erase(std::remove(v.begin(), v.end(), i), v.end());
    if (v.empty()) super_.erase(sit);
  }
  freeSlot(i);
}

void BlockMap::orderFreeSlots() {
  // findOrCreate takes the back: descending order hands out the lowest slot first. The slots
  // freed since the last call are sorted and merged into those already in order.
  const auto middle = free_.begin() + static_cast<std::ptrdiff_t>(free_sorted_);
  std::sort(middle, free_.end(), std::greater<BlockIndex>());
  std::inplace_merge(free_.begin(), middle, free_.end(), std::greater<BlockIndex>());
  free_sorted_ = free_.size();
}

void BlockMap::erase(const std::vector<BlockKey>& keys) {
  std::vector<char> gone(meta_.size(), 0);
  std::vector<BlockKey> lists;
  lists.reserve(keys.size());
  for (const BlockKey& key : keys) {
    const BlockIndex i = index_.find(key);
    if (i == kNoBlock) continue;
    index_.erase(key);
    gone[i] = 1;
    lists.push_back(superKeyOf(key));
    freeSlot(i);
  }
  std::sort(lists.begin(), lists.end(), [](const BlockKey& a, const BlockKey& b) {
    return std::tie(a.z, a.y, a.x) < std::tie(b.z, b.y, b.x);
  });
  lists.erase(std::unique(lists.begin(), lists.end()), lists.end());
  for (const BlockKey& s : lists) {
    auto sit = super_.find(s);
    if (sit == super_.end()) continue;
    auto& v = sit->second;
    v.erase(std::remove_if(v.begin(), v.end(), [&](BlockIndex i) { return gone[i] != 0; }),
            v.end());
    if (v.empty()) super_.erase(sit);
  }
}

size_t BlockMap::releaseFreePages() {
  if (!allocator_->pagesReleasable() || free_.empty()) return 0;
  const size_t pages = meta_.size() / kBlocksPerPage;  // whole pages in use by the arena
  std::vector<uint8_t> free_blocks(meta_.size(), 0);
  for (BlockIndex i : free_) free_blocks[i] = 1;
  page_released_.resize(pages, 0);
  size_t released = 0;
  size_t run_start = 0, run_length = 0;  // consecutive pages of one chunk to release
  auto flush = [&] {
    // Each call is a TLB shootdown on every core (on a VM an interrupt to each): runs shorter
    // than kMinReleasePages stay (paged W4 on the 2-core VM made ~31,800 calls, most of one or
    // two pages, ~4.8 s of the map's thread); the next blocks fill them first anyway.
    if (run_length < kMinReleasePages) {
      run_length = 0;
      return;
    }
    const BlockIndex first = static_cast<BlockIndex>(run_start * kBlocksPerPage);
    if (madvise(&block(first), run_length * kPageBytes, MADV_DONTNEED) == 0) {
      for (size_t p = run_start; p < run_start + run_length; ++p) page_released_[p] = 1;
      released += run_length * kPageBytes;
    }
    run_length = 0;
  };
  constexpr size_t kPagesPerChunk = kBlocksPerChunk / kBlocksPerPage;
  for (size_t p = 0; p < pages; ++p) {
    if (p % kPagesPerChunk == 0) flush();  // chunks are not contiguous
    bool all_free = !page_released_[p];
    for (size_t b = 0; all_free && b < kBlocksPerPage; ++b)
      all_free = free_blocks[p * kBlocksPerPage + b] != 0;
    if (!all_free) {
      flush();
      continue;
    }
    if (run_length == 0) run_start = p;
    ++run_length;
  }
  flush();
  return released;
}

void BlockMap::clear() {
  page_released_.clear();  // releasing a page twice is harmless
  changes_.clear();
  index_.clear();
  super_.clear();
  free_.clear();
  free_sorted_ = 0;
  for (BlockIndex i = static_cast<BlockIndex>(meta_.size()); i-- > 0;) freeSlot(i);
}

void BlockMap::freeSlot(BlockIndex i) {
  // No key and no stamps: walks over the slots (BlockView::changedSlotsSince) skip it.
  BlockMeta& m = meta_[i];
  m.key = kFreedSlotKey;
  m.changed_at = m.occupied_at = m.state_at = m.masks_at = 0;
  free_.push_back(i);
}

void BlockMap::forEachInBox(const BlockKey& lo, const BlockKey& hi,
                            const std::function<void(BlockIndex)>& fn) const {
  if (index_.empty() || lo.x > hi.x || lo.y > hi.y || lo.z > hi.z) return;
  const BlockKey slo = superKeyOf(lo), shi = superKeyOf(hi);
  const double box_supers =
      (double(shi.x) - slo.x + 1) * (double(shi.y) - slo.y + 1) * (double(shi.z) - slo.z + 1);
  auto inside = [&](const BlockKey& k) {
    return k.x >= lo.x && k.x <= hi.x && k.y >= lo.y && k.y <= hi.y && k.z >= lo.z && k.z <= hi.z;
  };
  if (box_supers > static_cast<double>(super_.size())) {
    for (const auto& [skey, list] : super_) {
      if (skey.x < slo.x || skey.x > shi.x || skey.y < slo.y || skey.y > shi.y || skey.z < slo.z ||
          skey.z > shi.z)
        continue;
      for (BlockIndex i : list)
        if (inside(meta_[i].key)) fn(i);
    }
    return;
  }
  for (int32_t z = slo.z; z <= shi.z; ++z)
    for (int32_t y = slo.y; y <= shi.y; ++y)
      for (int32_t x = slo.x; x <= shi.x; ++x) {
        auto it = super_.find(BlockKey{x, y, z});
        if (it == super_.end()) continue;
        for (BlockIndex i : it->second)
          if (inside(meta_[i].key)) fn(i);
      }
}

void BlockMap::forEach(const std::function<void(BlockIndex)>& fn) const {
  index_.forEach([&](const BlockKey&, BlockIndex i) { fn(i); });
}

void BlockMap::forEachCoarseCell(
    const std::function<void(const std::vector<BlockIndex>&)>& fn) const {
  for (const auto& [skey, list] : super_)
    if (!list.empty()) fn(list);
}

KeyBounds BlockMap::observedBounds() const {
  KeyBounds b;
  index_.forEach([&](const BlockKey& key, BlockIndex i) {
    const Block& blk = block(i);
    for (int c = 0; c < kCellsPerBlock; ++c) {
      if (!blk.cells[c].observed()) continue;
      const VoxelKey v = voxelKeyOf(key, c);
      if (b.empty) {
        b.min = b.max = v;
        b.empty = false;
        continue;
      }
      b.min = {std::min(b.min.x, v.x), std::min(b.min.y, v.y), std::min(b.min.z, v.z)};
      b.max = {std::max(b.max.x, v.x), std::max(b.max.y, v.y), std::max(b.max.z, v.z)};
    }
  });
  return b;
}

void BlockMap::recomputeMasks(const std::vector<BlockIndex>& indices, const OccupancyModel& model) {
  const long n = static_cast<long>(indices.size());
#pragma omp parallel for schedule(static) if (n > 256)
  for (long j = 0; j < n; ++j) masks_[indices[j]] = stateMasksOf(block(indices[j]), model);
}

void BlockMap::recomputeAllMasks(const OccupancyModel& model) {
  std::vector<BlockIndex> live;
  live.reserve(size());
  forEach([&](BlockIndex i) { live.push_back(i); });
  recomputeMasks(live, model);
}

bool BlockMap::masksChangedSince(uint64_t revision, std::vector<BlockKey>* out) const {
  std::vector<BlockIndex> indices;
  if (!masksChangedSince(revision, &indices)) return false;
  out->clear();
  out->reserve(indices.size());
  for (const BlockIndex i : indices) out->push_back(meta_[i].key);
  return true;
}

bool BlockMap::masksChangedSince(uint64_t revision, std::vector<BlockIndex>* out,
                                 ListOrder order) const {
  if (!changes_.reaches(revision)) return false;
  out->clear();
  if (slotsOfRecordsServe(revision, out, order)) return true;
  out->clear();
  // The keys' blocks looked up in parallel (a scan changes tens of thousands: the lookups are
  // the list's cost), then each index kept once in the log's order (a block erased and made
  // again within one revision is recorded twice).
  const std::vector<BlockKey> keys = changes_.keysAfter(revision);
  const int64_t n = static_cast<int64_t>(keys.size());
  std::vector<BlockIndex> found(keys.size());
#pragma omp parallel for schedule(static) if (n > 4096)
  for (int64_t j = 0; j < n; ++j) found[j] = index_.find(keys[j]);
  std::vector<uint8_t> listed(meta_.size(), 0);
  out->reserve(found.size());
  for (const BlockIndex i : found) {
    if (i == kNoBlock || listed[i]) continue;
    listed[i] = 1;
    out->push_back(i);
  }
  if (order == ListOrder::kSlots) std::sort(out->begin(), out->end());
  return true;
}

bool BlockMap::slotsOfRecordsServe(uint64_t revision, std::vector<BlockIndex>* out,
                                   ListOrder order) const {
  // The slots the records name, each once in the log's order, without a look-up by key: a
  // question spanning several revisions reads each block's records several times (ten W1
  // clouds: ~500 k records for ~100 k blocks), and a hash of their keys cost 20-60 ms on two
  // cores. It serves when every record's key is the block its slot holds now; a block erased
  // since (its slot free or another block's) sends the question to the look-ups by key.
  const size_t slots = meta_.size();
  std::vector<uint32_t> at(slots, 0);  // a slot's place in `out` + 1
  std::vector<BlockKey> keys;          // the key first recorded with each listed slot
  bool serves = true;
  changes_.forEachAfter(revision, [&](const BlockKey& key, uint32_t slot) {
    if (!serves) return;
    if (slot >= slots) {
      serves = false;  // a record without its slot (or of a block beyond the map's slots)
      return;
    }
    const uint32_t place = at[slot];
    if (place == 0) {
      at[slot] = static_cast<uint32_t>(out->size()) + 1;
      out->push_back(slot);
      keys.push_back(key);
    } else if (!(keys[place - 1] == key)) {
      serves = false;  // two blocks recorded at one slot: one of them was erased
    }
  });
  if (!serves) return false;
  // Each listed slot holds the block its records name (checked in parallel: the metadata is
  // read at random).
  const int64_t n = static_cast<int64_t>(out->size());
  int64_t stale = 0;
#pragma omp parallel for schedule(static) reduction(+ : stale) if (n > 4096)
  for (int64_t j = 0; j < n; ++j) stale += meta_[(*out)[j]].key == keys[j] ? 0 : 1;
  if (stale != 0) return false;
  if (order == ListOrder::kSlots) {
    // Ascending: the listed slots read off the places array, which is indexed by slot.
    out->clear();
    for (size_t s = 0; s < slots; ++s)
      if (at[s] != 0) out->push_back(static_cast<BlockIndex>(s));
  }
  return true;
}

size_t BlockMap::hostBytes() const {
  // Cells in the arena, per-block metadata and masks, the index's slots and the coarse index.
  return chunks_.size() * kBlocksPerChunk * sizeof(Block) + meta_.capacity() * sizeof(BlockMeta) +
         masks_.capacity() * sizeof(BlockStateMasks) + changes_.bytes() + index_.bytes() +
         super_.size() * (sizeof(BlockKey) + 3 * sizeof(void*) + 2 * sizeof(void*));
}

}  // namespace fragg
