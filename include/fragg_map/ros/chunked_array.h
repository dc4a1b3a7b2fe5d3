// An array that grows by whole chunks and never moves what it holds: for the server's
// per-block arrays that grow with the map at publication time (MaskMirror). A std::vector that
// doubles copies every element it holds into fresh memory at the publication that crosses its
// capacity (the mirror's keys, masks and stamps: ~156 B a block, a copy of tens of MB and the
// page faults of twice that, 25-50 ms on the 2-core machine, on one cloud's latency); here
// growth allocates only the new chunks, and touches only the elements it makes. Indexing is two
// loads (chunk, element).
#pragma once

#include <cstddef>
#include <memory>
#include <new>
#include <type_traits>
#include <vector>

namespace fragg::ros {

template <class T, unsigned kChunkBits = 16>
class ChunkedArray {
  static_assert(std::is_trivially_destructible_v<T>, "elements are dropped without a destructor");

 public:
  static constexpr size_t kChunk = size_t{1} << kChunkBits;

  /// Elements held.
  [[nodiscard]] size_t size() const { return size_; }
  /// Element `i` (< size()).
  [[nodiscard]] T& operator[](size_t i) { return chunks_[i >> kChunkBits].get()[i & (kChunk - 1)]; }
  [[nodiscard]] const T& operator[](size_t i) const {
    return chunks_[i >> kChunkBits].get()[i & (kChunk - 1)];
  }
  /// Grows to (or shrinks to) `n` elements; new elements are value-initialised. Elements below
  /// min(n, size()) keep their values and addresses. A chunk's memory is allocated without being
  /// written: only the elements in use are touched (a fresh 2 MiB page costs ms on a VM).
  void resize(size_t n) {
    const size_t chunks = (n + kChunk - 1) >> kChunkBits;
    while (chunks_.size() < chunks)
      chunks_.emplace_back(static_cast<T*>(::operator new(kChunk * sizeof(T))));
    for (size_t i = size_; i < n; ++i) new (&(*this)[i]) T();
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
  struct FreeChunk {
    void operator()(T* p) const { ::operator delete(p); }
  };
  std::vector<std::unique_ptr<T, FreeChunk>> chunks_;
  size_t size_ = 0;
};

}  // namespace fragg::ros
