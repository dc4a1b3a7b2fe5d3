#include "fragg_map/block_view.h"

namespace fragg {

void BlockView::forEach(const BlockVisitor& fn) const {
  blocks_->forEach([&](BlockIndex i) { fn(blocks_->meta(i).key, blocks_->block(i)); });
}

void BlockView::forEachIn(const BlockKey& lo, const BlockKey& hi, const BlockVisitor& fn) const {
  blocks_->forEachInBox(lo, hi, [&](BlockIndex i) { fn(blocks_->meta(i).key, blocks_->block(i)); });
}

std::vector<BlockRef> BlockView::all() const {
  std::vector<BlockRef> out;
  out.reserve(blocks_->size());
  blocks_->forEach([&](BlockIndex i) {
    out.push_back({blocks_->meta(i).key, &blocks_->block(i)});
  });
  return out;
}

std::vector<BlockRef> BlockView::in(const BlockKey& lo, const BlockKey& hi) const {
  std::vector<BlockRef> out;
  blocks_->forEachInBox(lo, hi, [&](BlockIndex i) {
    out.push_back({blocks_->meta(i).key, &blocks_->block(i)});
  });
  return out;
}

BlockStamps BlockView::stamps(const BlockKey& key) const {
  const BlockIndex i = blocks_->find(key);
  if (i == kNoBlock) return {};
  const BlockMeta& m = blocks_->meta(i);
  return {m.changed_at, m.occupied_at, m.state_at};
}

namespace {
uint64_t stampOf(const BlockMeta& m, BlockChange what) {
  return what == BlockChange::kOccupied ? m.occupied_at
         : what == BlockChange::kState  ? m.state_at
                                        : m.changed_at;
}
}  // namespace

std::vector<BlockKey> BlockView::changedSince(uint64_t revision, BlockChange what) const {
  std::vector<BlockKey> out;
  blocks_->forEach([&](BlockIndex i) {
    const BlockMeta& m = blocks_->meta(i);
    if (stampOf(m, what) > revision) out.push_back(m.key);
  });
  return out;
}

std::vector<BlockRef> BlockView::changedRefsSince(uint64_t revision, BlockChange what) const {
  std::vector<BlockRef> out;
  blocks_->forEach([&](BlockIndex i) {
    const BlockMeta& m = blocks_->meta(i);
    if (stampOf(m, what) > revision) out.push_back({m.key, &blocks_->block(i)});
  });
  return out;
}

}  // namespace fragg
