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

/// Appends the slots whose `what` stamp is after `revision` to `out`, ascending: the metadata
/// read in storage order (free slots carry no stamps), where a walk through the index reads it
/// at random.
void stampedAfter(const BlockMap& blocks, uint64_t revision, BlockChange what,
                  std::vector<BlockIndex>* out) {
  const BlockIndex n = static_cast<BlockIndex>(blocks.slotCount());
  for (BlockIndex i = 0; i < n; ++i)
    if (stampOf(blocks.meta(i), what) > revision) out->push_back(i);
}

std::vector<BlockIndex> stampedAfter(const BlockMap& blocks, uint64_t revision, BlockChange what) {
  std::vector<BlockIndex> out;
  stampedAfter(blocks, revision, what, &out);
  return out;
}
}  // namespace

std::vector<BlockIndex> BlockView::allSlots() const {
  std::vector<BlockIndex> out;
  out.reserve(blocks_->size());
  const BlockIndex n = static_cast<BlockIndex>(blocks_->slotCount());
  for (BlockIndex i = 0; i < n; ++i)
    if (blocks_->liveAt(i)) out.push_back(i);
  return out;
}

std::vector<BlockIndex> BlockView::changedSlotsSince(uint64_t revision, BlockChange what) const {
  std::vector<BlockIndex> out;
  changedSlotsSince(revision, what, &out);
  return out;
}

void BlockView::changedSlotsSince(uint64_t revision, BlockChange what,
                                  std::vector<BlockIndex>* out) const {
  out->clear();
  if (what == BlockChange::kMasks &&
      blocks_->masksChangedSince(revision, out, BlockMap::ListOrder::kSlots))
    return;
  stampedAfter(*blocks_, revision, what, out);
}

std::vector<BlockKey> BlockView::changedSince(uint64_t revision, BlockChange what) const {
  std::vector<BlockKey> out;
  if (what == BlockChange::kMasks && blocks_->masksChangedSince(revision, &out)) return out;
  const std::vector<BlockIndex> slots = stampedAfter(*blocks_, revision, what);
  out.reserve(slots.size());
  for (const BlockIndex i : slots) out.push_back(blocks_->meta(i).key);
  return out;
}

std::vector<BlockRef> BlockView::changedRefsSince(uint64_t revision, BlockChange what) const {
  std::vector<BlockRef> out;
  std::vector<BlockIndex> slots;
  if (what != BlockChange::kMasks || !blocks_->masksChangedSince(revision, &slots))
    slots = stampedAfter(*blocks_, revision, what);
  out.reserve(slots.size());
  for (const BlockIndex i : slots) out.push_back({blocks_->meta(i).key, &blocks_->block(i)});
  return out;
}

}  // namespace fragg
