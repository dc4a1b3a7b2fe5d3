// DeviceScratch on the CUDA runtime: numbered device and pinned buffers and one stream.
#include "fragg_map/device_scratch.h"

#include <map>

#include "cuda_array.h"
#include "cuda_check.h"
#include "cuda_stream.h"

namespace fragg {

namespace cuda {
namespace {

class CudaScratch final : public DeviceScratch {
 public:
  explicit CudaScratch(int device) : device_(device) {}

  void* deviceBuffer(int id, size_t bytes) override {
    FRAGG_CUDA_CHECK(cudaSetDevice(device_));
    DeviceArray<unsigned char>& a = device_buffers_[id];
    a.reserve(bytes);
    return a.get();
  }
  void* pinnedBuffer(int id, size_t bytes) override {
    FRAGG_CUDA_CHECK(cudaSetDevice(device_));
    PinnedArray<unsigned char>& a = pinned_buffers_[id];
    a.reserve(bytes);
    return a.get();
  }
  void* stream() const override { return stream_->get(); }
  int device() const override { return device_; }
  size_t deviceBytes() const override {
    size_t n = 0;
    for (const auto& [id, a] : device_buffers_) n += a.bytes();
    return n;
  }

 private:
  /// The device is selected before the stream is made on it.
  static std::unique_ptr<CudaStream> streamOn(int device) {
    FRAGG_CUDA_CHECK(cudaSetDevice(device));
    return std::make_unique<CudaStream>();
  }

  int device_;
  std::unique_ptr<CudaStream> stream_ = streamOn(device_);
  std::map<int, DeviceArray<unsigned char>> device_buffers_;
  std::map<int, PinnedArray<unsigned char>> pinned_buffers_;
};

}  // namespace
}  // namespace cuda

std::unique_ptr<DeviceScratch> makeDeviceScratch(int device) {
  return std::make_unique<cuda::CudaScratch>(device);
}

}  // namespace fragg
