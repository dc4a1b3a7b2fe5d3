// An array that grows by whole chunks and never moves what it holds: for the server's
// per-block arrays that grow with the map at publication time (MaskMirror). A std::vector that
// doubles copies every element it holds into fresh memory at the publication that crosses its
// capacity (the mirror's keys, masks and stamps: ~156 B a block, a copy of tens of MB and the
// page faults of twice that, 25-50 ms on the 2-core machine, on one cloud's latency); here
// growth allocates only the new chunks. Indexing is two loads (chunk, element).
#pragma once

#include <cstddef>
#include <memory>
#include <vector>

namespace fragg::ros {

template <class T, unsigned kChunkBits = 16>
class ChunkedArray {
 public:
  static constexpr size_t kChunk = size_t{1} << kChunkBits;

  /// Elements held.
  [[nodiscard]] size_t size() const { return size_; }
  /// Element `i` (< size()).
  [[nodiscard]] T& operator[](size_t i) { return chunks_[i >> kChunkBits][i & (kChunk - 1)]; }
  [[nodiscard]] const T& operator[](size_t i) const {
    return chunks_[i >> kChunkBits][i & (kChunk - 1)];
  }
  /// Grows to (or shrinks to) `n` elements; new elements are value-initialised (a chunk is when
  /// it is allocated). Elements below min(n, size()) keep their addresses.
  void resize(size_t n) {
    const size_t chunks = (n + kChunk - 1) >> kChunkBits;
    while (chunks_.size() < chunks) chunks_.push_back(std::make_unique<T[]>(kChunk));
    // Elements past a shrink are reset, so that growing again finds them value-initialised.
    for (size_t i = n; i < size_; ++i) (*this)[i] = T();
    size_ = n;
  }
  /// Appends `v`.
  void push_back(const T& v) {
    resize(size_ + 1);
    (*this)[size_ - 1] = v;
  }
  /// Empties the array and hands its chunks back.
  void clear() {
    chunks_.clear();
    size_ = 0;
  }

 private:
  std::vector<std::unique_ptr<T[]>> chunks_;
  size_t size_ = 0;
};

}  // namespace fragg::ros
