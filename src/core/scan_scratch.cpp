#include "fragg_map/internal/scan_scratch.h"

#include <cstring>
#include <string>

#include "fragg_map/errors.h"

namespace fragg {

namespace {
constexpr int kSuperBits = kBlockBits;  // a superblock is 8^3 blocks
constexpr int kSuperMask = (1 << kSuperBits) - 1;
constexpr int64_t kMaxTableEntries = int64_t{1} << 26;  // 256 MiB of table at most
}  // namespace

void ScanScratch::begin(const BlockKey& lo, const BlockKey& hi) {
  super_lo_ = {lo.x >> kSuperBits, lo.y >> kSuperBits, lo.z >> kSuperBits};
  dim_x_ = int64_t{hi.x >> kSuperBits} - super_lo_.x + 1;
  dim_y_ = int64_t{hi.y >> kSuperBits} - super_lo_.y + 1;
  dim_z_ = int64_t{hi.z >> kSuperBits} - super_lo_.z + 1;
  const int64_t entries = dim_x_ * dim_y_ * dim_z_;
  if (entries > kMaxTableEntries)
    throw InvalidArgument("scan spans " + std::to_string(entries) +
                          " superblocks; limit the sensor's max range or coarsen the resolution");
  if (static_cast<int64_t>(table_.size()) < entries) {
    std::vector<std::atomic<ScratchNode*>> bigger(static_cast<size_t>(entries));
    for (auto& e : bigger) e.store(nullptr, std::memory_order_relaxed);
    table_.swap(bigger);
  }
}

ScratchBlock& ScanScratch::blockFor(const BlockKey& key) {
  const int64_t sx = (key.x >> kSuperBits) - super_lo_.x;
  const int64_t sy = (key.y >> kSuperBits) - super_lo_.y;
  const int64_t sz = (key.z >> kSuperBits) - super_lo_.z;
  const uint32_t t = static_cast<uint32_t>((sz * dim_y_ + sy) * dim_x_ + sx);
  ScratchNode* node = table_[t].load(std::memory_order_acquire);
  if (!node) {
    ScratchNode* fresh = &nodes_[nodes_.allocate()];
    fresh->table_index = t;
    if (table_[t].compare_exchange_strong(node, fresh, std::memory_order_acq_rel))
      node = fresh;  // else `node` holds the winner's; `fresh` stays unused (and zero)
  }
  const int local = (key.x & kSuperMask) | ((key.y & kSuperMask) << kSuperBits) |
                    ((key.z & kSuperMask) << (2 * kSuperBits));
  ScratchBlock** slot = &node->blocks[local];
  ScratchBlock* block = __atomic_load_n(slot, __ATOMIC_ACQUIRE);
  if (!block) {
    ScratchBlock* fresh = &blocks_[blocks_.allocate()];
    fresh->key = key;
    if (__atomic_compare_exchange_n(slot, &block, fresh, false, __ATOMIC_ACQ_REL,
                                    __ATOMIC_ACQUIRE)) {
      fresh->published = true;
      block = fresh;
    }
  }
  return *block;
}

void ScanScratch::end() {
  nodes_.reset([this](ScratchNode& n) {
    if (n.table_index < table_.size())
      table_[n.table_index].store(nullptr, std::memory_order_relaxed);
    std::memset(n.blocks, 0, sizeof(n.blocks));
    n.table_index = 0;
  });
  blocks_.reset([](ScratchBlock& b) {
    std::memset(b.free, 0, sizeof(b.free));
    std::memset(b.hit, 0, sizeof(b.hit));
    b.published = false;
  });
}

}  // namespace fragg
