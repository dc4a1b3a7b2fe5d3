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
  return {m.changed_at, m.occupied_at, m.state_at, m.masks_at};
}

namespace {
uint64_t stampOf(const BlockMeta& m, BlockChange what) {
  switch (what) {
    case BlockChange::kOccupied:
      return m.occupied_at;
    case BlockChange::kState:
      return m.state_at;
    case BlockChange::kMasks:
      return m.masks_at;
    case BlockChange::kAny:
      break;
  }
  return m.changed_at;
}
}  // namespace

std::vector<BlockKey> BlockView::changedSince(uint64_t revision, BlockChange what) const {
  std::vector<BlockKey> out;
  if (what == BlockChange::kMasks && blocks_->masksChangedSince(revision, &out)) return out;
  blocks_->forEach([&](BlockIndex i) {
    const BlockMeta& m = blocks_->meta(i);
    if (stampOf(m, what) > revision) out.push_back(m.key);
  });
  return out;
}

std::vector<BlockRef> BlockView::changedRefsSince(uint64_t revision, BlockChange what) const {
  std::vector<BlockRef> out;
  std::vector<BlockKey> keys;
  if (what == BlockChange::kMasks && blocks_->masksChangedSince(revision, &keys)) {
    out.reserve(keys.size());
    for (const BlockKey& key : keys) out.push_back({key, blocks_->findBlock(key)});
    return out;
  }
  blocks_->forEach([&](BlockIndex i) {
    const BlockMeta& m = blocks_->meta(i);
    if (stampOf(m, what) > revision) out.push_back({m.key, &blocks_->block(i)});
  });
  return out;
}

}  // namespace fragg
