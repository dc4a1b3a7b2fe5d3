#include "fragg_map/internal/scan_scratch.h"

#include <cstring>
#include <string>

#include "fragg_map/errors.h"

namespace fragg {

namespace {
constexpr int kSuperBits = kBlockBits;  // a superblock is 8^3 blocks
constexpr int kSuperMask = (1 << kSuperBits) - 1;
constexpr int64_t kMaxTableEntries = int64_t{1} << 26;  // 512 MiB of table at most
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
  if (static_cast<int64_t>(table_.size()) < entries)
    table_.assign(static_cast<size_t>(entries), nullptr);
}

ScratchBlock& ScanScratch::blockFor(const BlockKey& key) {
  const int64_t sx = (key.x >> kSuperBits) - super_lo_.x;
  const int64_t sy = (key.y >> kSuperBits) - super_lo_.y;
  const int64_t sz = (key.z >> kSuperBits) - super_lo_.z;
  const uint32_t t = static_cast<uint32_t>((sz * dim_y_ + sy) * dim_x_ + sx);
  Node*& node = table_[t];
  if (!node) {
    if (used_nodes_ == nodes_.size()) nodes_.push_back(std::make_unique<Node>());
    node = nodes_[used_nodes_++].get();
    std::memset(node->blocks, 0, sizeof(node->blocks));
    node->table_index = t;
  }
  const int local = (key.x & kSuperMask) | ((key.y & kSuperMask) << kSuperBits) |
                    ((key.z & kSuperMask) << (2 * kSuperBits));
  ScratchBlock*& block = node->blocks[local];
  if (!block) {
    if (used_blocks_ == blocks_.size()) blocks_.push_back(std::make_unique<ScratchBlock>());
    block = blocks_[used_blocks_++].get();
    *block = ScratchBlock{};
    block->key = key;
    block->index = static_cast<uint32_t>(used_blocks_ - 1);
  }
  return *block;
}

const ScratchBlock* ScanScratch::find(const BlockKey& key) const {
  const int64_t sx = (key.x >> kSuperBits) - super_lo_.x;
  const int64_t sy = (key.y >> kSuperBits) - super_lo_.y;
  const int64_t sz = (key.z >> kSuperBits) - super_lo_.z;
  if (sx < 0 || sy < 0 || sz < 0 || sx >= dim_x_ || sy >= dim_y_ || sz >= dim_z_) return nullptr;
  const Node* node = table_[static_cast<size_t>((sz * dim_y_ + sy) * dim_x_ + sx)];
  if (!node) return nullptr;
  const int local = (key.x & kSuperMask) | ((key.y & kSuperMask) << kSuperBits) |
                    ((key.z & kSuperMask) << (2 * kSuperBits));
  return node->blocks[local];
}

void ScanScratch::end() {
  for (size_t i = 0; i < used_nodes_; ++i) table_[nodes_[i]->table_index] = nullptr;
  used_nodes_ = 0;
  used_blocks_ = 0;
}

}  // namespace fragg
