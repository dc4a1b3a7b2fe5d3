// One RAII array type for the two kinds of CUDA memory the backend uses: device memory and
// page-locked (pinned) host memory. Copies between them are explicit (cuda_stream.h).
#pragma once

#include <cuda_runtime.h>

#include <cstddef>
#include <utility>

#include "cuda_check.h"

namespace fragg::cuda {

enum class MemorySpace { kDevice, kPinnedHost };

template <class T, MemorySpace kSpace>
class CudaArray {
 public:
  CudaArray() = default;
  explicit CudaArray(size_t n) { resize(n); }
  ~CudaArray() { release(); }
  CudaArray(CudaArray&& o) noexcept
      : p_(std::exchange(o.p_, nullptr)), n_(std::exchange(o.n_, 0)) {}
  CudaArray& operator=(CudaArray&& o) noexcept {
    if (this != &o) {
      release();
      p_ = std::exchange(o.p_, nullptr);
      n_ = std::exchange(o.n_, 0);
    }
    return *this;
  }
  CudaArray(const CudaArray&) = delete;
  CudaArray& operator=(const CudaArray&) = delete;

  /// Reallocates (contents lost) unless it already has `n` elements.
  void resize(size_t n) {
    if (n == n_) return;
    release();
    if (n) allocate(n);
    n_ = n;
  }
  /// Grows (contents lost) when smaller than `n`, by at least half again.
  void reserve(size_t n) {
    if (n > n_) resize(n + n / 2);
  }
  T* get() const { return p_; }
  /// Host memory only.
  T& operator[](size_t i) const { return p_[i]; }
  size_t size() const { return n_; }
  size_t bytes() const { return n_ * sizeof(T); }

 private:
  void allocate(size_t n) {
    void* p = nullptr;
    if constexpr (kSpace == MemorySpace::kDevice)
      FRAGG_CUDA_CHECK(cudaMalloc(&p, n * sizeof(T)));
    else
      FRAGG_CUDA_CHECK(cudaHostAlloc(&p, n * sizeof(T), cudaHostAllocPortable));
    p_ = static_cast<T*>(p);
  }
  void release() {
    if (p_) {
      if constexpr (kSpace == MemorySpace::kDevice)
        cudaFree(p_);
      else
        cudaFreeHost(p_);
    }
    p_ = nullptr;
    n_ = 0;
  }
  T* p_ = nullptr;
  size_t n_ = 0;
};

template <class T>
using DeviceArray = CudaArray<T, MemorySpace::kDevice>;
template <class T>
using PinnedArray = CudaArray<T, MemorySpace::kPinnedHost>;

}  // namespace fragg::cuda
