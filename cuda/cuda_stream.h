// A CUDA stream and events (RAII), and the explicit copies between host and device.
#pragma once

#include <cuda_runtime.h>

#include <cstddef>

#include "cuda_check.h"

namespace fragg::cuda {

class CudaStream {
 public:
  CudaStream() { FRAGG_CUDA_CHECK(cudaStreamCreateWithFlags(&s_, cudaStreamNonBlocking)); }
  ~CudaStream() { cudaStreamDestroy(s_); }
  CudaStream(const CudaStream&) = delete;
  CudaStream& operator=(const CudaStream&) = delete;
  cudaStream_t get() const { return s_; }
  void sync() const { FRAGG_CUDA_CHECK(cudaStreamSynchronize(s_)); }

 private:
  cudaStream_t s_ = nullptr;
};

class CudaEvent {
 public:
  CudaEvent() { FRAGG_CUDA_CHECK(cudaEventCreate(&e_)); }
  ~CudaEvent() { cudaEventDestroy(e_); }
  CudaEvent(const CudaEvent&) = delete;
  CudaEvent& operator=(const CudaEvent&) = delete;
  void record(cudaStream_t stream) { FRAGG_CUDA_CHECK(cudaEventRecord(e_, stream)); }
  /// Makes `stream` wait for the work recorded before this event (its latest record).
  void makeWait(cudaStream_t stream) const { FRAGG_CUDA_CHECK(cudaStreamWaitEvent(stream, e_, 0)); }
  /// Waits for the work recorded before this event (not for what the stream got since).
  void synchronize() const { FRAGG_CUDA_CHECK(cudaEventSynchronize(e_)); }
  /// Seconds from `start` to this event (both recorded and complete).
  double secondsSince(const CudaEvent& start) const {
    float ms = 0.f;
    FRAGG_CUDA_CHECK(cudaEventElapsedTime(&ms, start.e_, e_));
    return ms * 1e-3;
  }

 private:
  cudaEvent_t e_ = nullptr;
};

/// Copies `n` elements host -> device / device -> host on `stream`.
template <class T>
void copyToDevice(T* dst, const T* src, size_t n, cudaStream_t stream) {
  if (n) FRAGG_CUDA_CHECK(cudaMemcpyAsync(dst, src, n * sizeof(T), cudaMemcpyHostToDevice, stream));
}
template <class T>
void copyToHost(T* dst, const T* src, size_t n, cudaStream_t stream) {
  if (n) FRAGG_CUDA_CHECK(cudaMemcpyAsync(dst, src, n * sizeof(T), cudaMemcpyDeviceToHost, stream));
}

}  // namespace fragg::cuda
