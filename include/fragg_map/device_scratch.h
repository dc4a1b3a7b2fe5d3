// Device working memory for readers of the layers (DESIGN §12): numbered buffers that are kept
// and grown between calls, and a stream to run on, on one CUDA device. A map on the CUDA
// backend owns one (lent with its device view, Map::deviceView), so a planning product's
// buffers are the map's state and go with it; makeDeviceScratch() makes a free-standing one.
// No CUDA header here: pointers are device (or pinned host) memory, the stream a cudaStream_t.
#pragma once

#include <cstddef>
#include <memory>

namespace fragg {

class DeviceScratch {
 public:
  virtual ~DeviceScratch() = default;
  /// Device memory of buffer `id`, at least `bytes` long (grown when shorter: the old contents
  /// are then lost). Throws CudaOutOfMemory when the device cannot give it.
  [[nodiscard]] virtual void* deviceBuffer(int id, size_t bytes) = 0;
  /// Pinned host memory of buffer `id` (its own numbering), likewise.
  [[nodiscard]] virtual void* pinnedBuffer(int id, size_t bytes) = 0;
  /// The stream the buffers' work runs on (a cudaStream_t).
  [[nodiscard]] virtual void* stream() const = 0;
  /// The CUDA device of the buffers and the stream.
  [[nodiscard]] virtual int device() const = 0;
  /// Device bytes held.
  [[nodiscard]] virtual size_t deviceBytes() const = 0;

  /// deviceBuffer() as `n` elements of T (at least one).
  template <class T>
  [[nodiscard]] T* device(int id, size_t n) {
    return static_cast<T*>(deviceBuffer(id, (n ? n : 1) * sizeof(T)));
  }
  /// pinnedBuffer() as `n` elements of T (at least one).
  template <class T>
  [[nodiscard]] T* pinned(int id, size_t n) {
    return static_cast<T*>(pinnedBuffer(id, (n ? n : 1) * sizeof(T)));
  }
};

/// A scratch of its own on CUDA device `device` (with its own stream). Throws CudaError when
/// the device cannot be used, InvalidArgument in a build without CUDA.
[[nodiscard]] std::unique_ptr<DeviceScratch> makeDeviceScratch(int device);

}  // namespace fragg
