// An array held twice, in pinned host memory and on the device, copied explicitly between
// the two on a stream (transfer lists, counters, window entries).
#pragma once

#include "cuda_array.h"
#include "cuda_stream.h"

namespace fragg::cuda {

template <class T>
class MirroredBuffer {
 public:
  /// Room for at least `n` elements on both sides (contents lost when it grows).
  void reserve(size_t n) {
    host_.reserve(n);
    device_.reserve(n);
  }
  T* host() const { return host_.get(); }
  T* device() const { return device_.get(); }
  T& operator[](size_t i) const { return host_[i]; }
  size_t size() const { return device_.size(); }
  size_t deviceBytes() const { return device_.bytes(); }
  /// The first `n` elements host -> device / device -> host.
  void toDevice(size_t n, cudaStream_t stream) const {
    copyToDevice(device_.get(), host_.get(), n, stream);
  }
  void toHost(size_t n, cudaStream_t stream) const {
    copyToHost(host_.get(), device_.get(), n, stream);
  }

 private:
  PinnedArray<T> host_;
  DeviceArray<T> device_;
};

}  // namespace fragg::cuda
