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
    std::vector<std::atomic<uint32_t>> bigger(static_cast<size_t>(entries));
    for (auto& e : bigger) e.store(0, std::memory_order_relaxed);
    table_.swap(bigger);
  }
}

ScratchBlock& ScanScratch::blockFor(const BlockKey& key) {
  const int64_t sx = (key.x >> kSuperBits) - super_lo_.x;
  const int64_t sy = (key.y >> kSuperBits) - super_lo_.y;
  const int64_t sz = (key.z >> kSuperBits) - super_lo_.z;
  const uint32_t t = static_cast<uint32_t>((sz * dim_y_ + sy) * dim_x_ + sx);
  uint32_t node_plus_one = table_[t].load(std::memory_order_acquire);
  if (node_plus_one == 0) {
    const uint32_t n = nodes_.allocate();
    nodes_[n].table_index = t;
    uint32_t expected = 0;
    if (table_[t].compare_exchange_strong(expected, n + 1, std::memory_order_acq_rel))
      node_plus_one = n + 1;
    else
      node_plus_one = expected;  // another thread won; node n stays unused (and zero)
  }
  ScratchNode& node = nodes_[node_plus_one - 1];
  const int local = (key.x & kSuperMask) | ((key.y & kSuperMask) << kSuperBits) |
                    ((key.z & kSuperMask) << (2 * kSuperBits));
  uint32_t* slot = &node.slot_plus_one[local];
  uint32_t block_plus_one = __atomic_load_n(slot, __ATOMIC_ACQUIRE);
  if (block_plus_one == 0) {
    const uint32_t b = blocks_.allocate();
    blocks_[b].key = key;
    uint32_t expected = 0;
    if (__atomic_compare_exchange_n(slot, &expected, b + 1, false, __ATOMIC_ACQ_REL,
                                    __ATOMIC_ACQUIRE)) {
      blocks_[b].published = true;
      block_plus_one = b + 1;
    } else {
      block_plus_one = expected;
    }
  }
  return blocks_[block_plus_one - 1];
}

void ScanScratch::end() {
  nodes_.reset([this](ScratchNode& n) {
    if (n.table_index < table_.size()) table_[n.table_index].store(0, std::memory_order_relaxed);
    std::memset(n.slot_plus_one, 0, sizeof(n.slot_plus_one));
    n.table_index = 0;
  });
  blocks_.reset([](ScratchBlock& b) {
    std::memset(b.flags, 0, sizeof(b.flags));
    b.published = false;
  });
}

}  // namespace fragg
