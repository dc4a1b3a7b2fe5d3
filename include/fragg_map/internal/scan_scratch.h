// Per-scan scratch of the CPU backend: a FREE bit and a HIT bit per touched cell (128 bytes a
// block, so the marks of a scan stay in cache), found through a dense table over the scan's
// bounding box in superblocks (8^3 blocks) and a 512-entry node per touched superblock.
// Threads mark cells concurrently: a bit is tested first and set with an atomic OR only the
// first time. Hit wins when the marks are applied.
#pragma once

#include <algorithm>
#include <atomic>
#include <cstdint>
#include <memory>
#include <mutex>
#include <new>
#include <vector>

#include "fragg_map/key.h"

namespace fragg {

/// Chunked pool of zero-initialised items; allocation is lock-free except for a new chunk.
template <class T, size_t kChunk>
class ChunkedPool {
 public:
  static constexpr size_t kMaxChunks = 1 << 16;
  ChunkedPool() : chunks_(kMaxChunks) {}
  ~ChunkedPool() {
    for (auto& c : chunks_) delete[] c.load();
  }
  uint32_t allocate() {
    const uint32_t i = count_.fetch_add(1, std::memory_order_relaxed);
    const size_t c = i / kChunk;
    if (c >= kMaxChunks) throw std::bad_alloc();
    if (!chunks_[c].load(std::memory_order_acquire)) {
      std::lock_guard<std::mutex> lock(mutex_);
      if (!chunks_[c].load(std::memory_order_relaxed))
        chunks_[c].store(new T[kChunk](), std::memory_order_release);
    }
    return i;
  }
  T& operator[](uint32_t i) { return chunks_[i / kChunk].load(std::memory_order_acquire)[i % kChunk]; }
  uint32_t size() const { return std::min<uint32_t>(count_.load(), capacity()); }
  uint32_t capacity() const {
    uint32_t n = 0;
    while (n < kMaxChunks && chunks_[n].load()) ++n;
    return n * kChunk;
  }
  /// Forgets all items; `zero(item)` must return each used item to its zero state.
  template <class Zero>
  void reset(Zero zero) {
    const uint32_t n = size();
    for (uint32_t i = 0; i < n; ++i) zero((*this)[i]);
    count_.store(0);
  }

 private:
  std::vector<std::atomic<T*>> chunks_;
  std::atomic<uint32_t> count_{0};
  std::mutex mutex_;
};

struct ScratchBlock {
  uint64_t free[kCellsPerBlock / 64];  ///< bit c: a ray passed through cell c
  uint64_t hit[kCellsPerBlock / 64];   ///< bit c: a ray ended in cell c
  BlockKey key;
  bool published;

  /// Marks cell `c` as passed through (or hit). Thread-safe.
  void mark(int c, bool is_hit) {
    uint64_t* word = (is_hit ? hit : free) + (c >> 6);
    const uint64_t bit = uint64_t{1} << (c & 63);
    if ((__atomic_load_n(word, __ATOMIC_RELAXED) & bit) == 0)
      __atomic_fetch_or(word, bit, __ATOMIC_RELAXED);
  }
};

struct ScratchNode {
  ScratchBlock* blocks[512];  ///< scratch block of each block in the superblock (null = none)
  uint32_t table_index;
};

class ScanScratch {
 public:
  /// Prepares the table for blocks in [lo, hi] (inclusive). Throws InvalidArgument when the
  /// box is too large (a scan spanning kilometres at centimetre resolution).
  void begin(const BlockKey& lo, const BlockKey& hi);

  /// Scratch block for `key` (inside the box), created on first use. Thread-safe.
  ScratchBlock& blockFor(const BlockKey& key);

  /// Calls fn(ScratchBlock&) for every block touched since begin().
  template <class Fn>
  void forEachTouched(Fn fn) {
    const uint32_t n = blocks_.size();
    for (uint32_t i = 0; i < n; ++i)
      if (blocks_[i].published) fn(blocks_[i]);
  }

  /// Returns everything to zero for the next scan (cost follows what was touched).
  void end();

 private:
  std::vector<std::atomic<ScratchNode*>> table_;  // node per superblock (null = none)
  BlockKey super_lo_;
  int64_t dim_x_ = 0, dim_y_ = 0, dim_z_ = 0;
  ChunkedPool<ScratchNode, 256> nodes_;
  ChunkedPool<ScratchBlock, 4096> blocks_;
};

}  // namespace fragg
