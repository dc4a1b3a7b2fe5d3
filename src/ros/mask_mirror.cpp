// The host copy of a map's keys and state masks that the server's outputs read.
#include "fragg_map/ros/mask_mirror.h"

#include <chrono>
#include <cstring>

#include "fragg_map/internal/reserve_headroom.h"

namespace fragg::ros {
namespace {

/// Cells free or occupied in `m`.
uint64_t knownIn(const fragg::BlockStateMasks& m) {
  uint64_t n = 0;
  for (int w = 0; w < fragg::kStateMaskWords; ++w)
    n += __builtin_popcountll(m.occupied[w] | m.free[w]);
  return n;
}

}  // namespace

const MaskMirror::SyncStats& MaskMirror::sync(const fragg::Map& map) {
  const auto t0 = std::chrono::steady_clock::now();
  const uint64_t revision = map.revision();
  stats_ = SyncStats();
  if (valid_ && revision >= revision_ && revision - revision_ <= accepted_lag_ &&
      map.viewEpoch() == epoch_ && map.resolution() == resolution_m_) {
    stats_.lagged = revision - revision_;
    return stats_;
  }
  // Blocks leave the map only with a new view epoch (masksChangedSince does not list them).
  const bool whole = !valid_ || map.viewEpoch() != epoch_ || revision < revision_ ||
                     map.resolution() != resolution_m_ ||
                     !map.masksChangedSince(revision_, &listed_keys_, &listed_masks_);
  stats_.list_seconds =
      std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
  if (whole) {
    rebuild(map);
  } else {
    stats_.listed = listed_keys_.size();
    const size_t before = keys_.size();
    applyListed(revision);
    stats_.added = keys_.size() - before;
  }
  valid_ = true;
  revision_ = revision;
  epoch_ = map.viewEpoch();
  resolution_m_ = map.resolution();
  stats_.seconds = std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
  return stats_;
}

void MaskMirror::rebuild(const fragg::Map& map) {
  const fragg::BlockView view = map.blockView();  // a CUDA map's changes written back once
  const std::vector<fragg::BlockIndex> slots = view.allSlots();
  table_.clear();
  keys_.clear();
  masks_.clear();
  masks_at_.clear();
  occupied_at_.clear();
  known_cells_ = 0;
  table_.reserve(slots.size());
  const uint64_t revision = map.revision();
  for (const fragg::BlockIndex s : slots) {
    table_.insert(view.keyAt(s), static_cast<uint32_t>(keys_.size()));
    keys_.push_back(view.keyAt(s));
    masks_.push_back(view.masksAt(s));
    known_cells_ += knownIn(view.masksAt(s));
    // Everything counts as changed at the rebuild's revision (readers rebuild with it).
    masks_at_.push_back(revision);
    occupied_at_.push_back(revision);
  }
  stats_.rebuilt = true;
  stats_.added = slots.size();
  ++generation_;
}

void MaskMirror::applyListed(uint64_t revision) {
  // The listed keys are distinct (Map::masksChangedSince): the blocks held already are updated
  // in parallel, each slot by one thread (a LiDAR second lists ~90 k blocks, most of them held);
  // the new ones are added after, in the list's order, as one by one.
  const auto started = std::chrono::steady_clock::now();
  const int64_t n = static_cast<int64_t>(listed_keys_.size());
  reserveWithHeadroom(&listed_slots_, listed_keys_.size());
  listed_slots_.resize(listed_keys_.size());
  int64_t known_change = 0;
  int64_t added = 0;
#pragma omp parallel for schedule(static) reduction(+ : known_change, added) if (n > 4096)
  for (int64_t j = 0; j < n; ++j) {
    const uint32_t s = table_.find(listed_keys_[j]);
    listed_slots_[j] = s;
    if (s == fragg::BlockKeyTable::kNone) {
      ++added;
      continue;
    }
    known_change += update(s, listed_masks_[j], revision);
  }
  known_cells_ = static_cast<uint64_t>(static_cast<int64_t>(known_cells_) + known_change);
  const auto updated = std::chrono::steady_clock::now();
  stats_.update_seconds = std::chrono::duration<double>(updated - started).count();
  if (added > 0) {
    // The new ones take the next slots in the list's order (as one by one), filled in parallel;
    // the index gets them in that order too.
    const size_t base = keys_.size();
    size_t next = base;
    for (int64_t j = 0; j < n; ++j)
      if (listed_slots_[j] == fragg::BlockKeyTable::kNone)
        listed_slots_[j] = static_cast<uint32_t>(next++);
    keys_.resize(next);
    masks_.resize(next);
    masks_at_.resize(next);
    occupied_at_.resize(next);
    uint64_t known_added = 0;
#pragma omp parallel for schedule(static) reduction(+ : known_added) if (n > 4096)
    for (int64_t j = 0; j < n; ++j) {
      const uint32_t s = listed_slots_[j];
      if (s < base) continue;
      const fragg::BlockStateMasks& masks = listed_masks_[j];
      keys_[s] = listed_keys_[j];
      masks_[s] = masks;
      masks_at_[s] = revision;
      bool occupied = false;
      for (const uint64_t w : masks.occupied) occupied |= w != 0;
      occupied_at_[s] = occupied ? revision : 0;
      known_added += knownIn(masks);
    }
    known_cells_ += known_added;
    table_.reserve(next);
    for (int64_t j = 0; j < n; ++j)
      if (listed_slots_[j] >= base) table_.insert(listed_keys_[j], listed_slots_[j]);
  }
  stats_.add_seconds =
      std::chrono::duration<double>(std::chrono::steady_clock::now() - updated).count();
}

int64_t MaskMirror::update(uint32_t s, const fragg::BlockStateMasks& masks, uint64_t revision) {
  fragg::BlockStateMasks& kept = masks_[s];
  if (std::memcmp(kept.occupied, masks.occupied, sizeof(kept.occupied)) != 0)
    occupied_at_[s] = revision;
  if (std::memcmp(&kept, &masks, sizeof(kept)) == 0) return 0;
  masks_at_[s] = revision;
  const int64_t change = static_cast<int64_t>(knownIn(masks)) - static_cast<int64_t>(knownIn(kept));
  kept = masks;
  return change;
}

std::vector<fragg::BlockIndex> MaskMirror::allSlots() const {
  std::vector<fragg::BlockIndex> out(keys_.size());
  for (size_t i = 0; i < out.size(); ++i) out[i] = static_cast<fragg::BlockIndex>(i);
  return out;
}

void MaskMirror::changedSlotsSince(uint64_t revision, fragg::BlockChange what,
                                   std::vector<fragg::BlockIndex>* out) const {
  out->clear();
  const ChunkedArray<uint64_t>& stamps =
      what == fragg::BlockChange::kOccupied ? occupied_at_ : masks_at_;
  for (size_t i = 0; i < stamps.size(); ++i)
    if (stamps[i] > revision) out->push_back(static_cast<fragg::BlockIndex>(i));
}

std::vector<fragg::BlockKey> MaskMirror::changedSince(uint64_t revision,
                                                      fragg::BlockChange what) const {
  std::vector<fragg::BlockIndex> slots;
  changedSlotsSince(revision, what, &slots);
  std::vector<fragg::BlockKey> keys;
  keys.reserve(slots.size());
  for (const fragg::BlockIndex s : slots) keys.push_back(keys_[s]);
  return keys;
}

}  // namespace fragg::ros
