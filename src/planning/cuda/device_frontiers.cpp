#include "device_frontiers.h"

#include <chrono>

#include "cuda_check.h"
#include "cuda_stream.h"
#include "fragg_map/errors.h"
#include "frontier_kernels.h"

namespace fragg::planning {

namespace {

/// The state's buffers in the tracker's scratch (device buffer ids; pinned: kCountersHost).
enum Buffer : int {
  kSeen = 1,
  kKeys,
  kValid,
  kBits,
  kCounts,
  kMarks,
  kExamine,
  kCounters,
  kOutKeys,
  kOutBits,
  kOutCount
};
enum PinnedBuffer : int { kCountersHost = 1, kOutCountHost };

double secondsSince(std::chrono::steady_clock::time_point t0) {
  return std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
}

/// The state's arrays for a pool of `n` slots, in `scratch` (kept between calls at one size).
cuda::FrontierSlots slotsIn(DeviceScratch& scratch, int32_t n) {
  cuda::FrontierSlots s;
  s.slots = n;
  s.seen = scratch.device<StateMasks>(kSeen, n);
  s.keys = scratch.device<BlockKey>(kKeys, n);
  s.valid = scratch.device<uint8_t>(kValid, n);
  s.bits = scratch.device<FrontierBits>(kBits, n);
  s.counts = scratch.device<uint32_t>(kCounts, n);
  s.marks = scratch.device<uint32_t>(kMarks, n);
  s.examine = scratch.device<int32_t>(kExamine, n);
  return s;
}

}  // namespace

DeviceFrontiers::DeviceFrontiers(const FrontierFilter& filter, int device)
    : filter_(filter), scratch_(makeDeviceScratch(device)) {
  if (filter.min_obstacle_distance_m > 0.0)
    throw InvalidArgument("device frontiers: the obstacle distance filter reads cells (host only)");
}

int DeviceFrontiers::device() const { return scratch_->device(); }

DeviceFrontierUpdate DeviceFrontiers::update(const DeviceLayerView& view, double resolution_m,
                                             const BlockKey& box_lo, const BlockKey& box_hi,
                                             bool full) {
  FRAGG_CUDA_CHECK(cudaSetDevice(scratch_->device()));
  const cudaStream_t stream = static_cast<cudaStream_t>(scratch_->stream());
  const int32_t n = view.slots;
  const cuda::FrontierSlots s = slotsIn(*scratch_, n);
  // A pool of another size renumbers nothing, but the buffers above were grown (their
  // contents lost): start again. Likewise when the update number wraps.
  if (n != slots_ || update_number_ == UINT32_MAX) full = true;
  if (full) {
    if (n > 0) {
      FRAGG_CUDA_CHECK(cudaMemsetAsync(s.valid, 0, size_t(n), stream));
      FRAGG_CUDA_CHECK(cudaMemsetAsync(s.counts, 0, size_t(n) * sizeof(uint32_t), stream));
      FRAGG_CUDA_CHECK(cudaMemsetAsync(s.marks, 0, size_t(n) * sizeof(uint32_t), stream));
    }
    slots_ = n;
    update_number_ = 0;
  }
  ++update_number_;
  cuda::FrontierKernelFilter f;
  f.resolution_m = resolution_m;
  f.use_box = filter_.use_box;
  if (f.use_box) {
    for (int a = 0; a < 3; ++a) {
      f.box_min_m[a] = filter_.box_min_m[a];
      f.box_max_m[a] = filter_.box_max_m[a];
    }
    f.box_lo = box_lo;
    f.box_hi = box_hi;
  }
  f.use_height = filter_.use_height;
  f.min_z_m = filter_.min_z_m;
  f.max_z_m = filter_.max_z_m;

  auto* counters = scratch_->device<cuda::FrontierCounters>(kCounters, 1);
  auto* counters_host = scratch_->pinned<cuda::FrontierCounters>(kCountersHost, 1);
  DeviceFrontierUpdate out;
  auto t0 = std::chrono::steady_clock::now();
  FRAGG_CUDA_CHECK(cudaMemsetAsync(counters, 0, sizeof(cuda::FrontierCounters), stream));
  cuda::launchFrontierCompare(view, s, f, update_number_, counters, stream);
  cuda::copyToHost(counters_host, counters, 1, stream);
  FRAGG_CUDA_CHECK(cudaStreamSynchronize(stream));
  const uint32_t listed = counters_host->examined;
  out.compare_seconds = secondsSince(t0);
  t0 = std::chrono::steady_clock::now();
  cuda::launchFrontierExamine(view, s, f, listed, counters, stream);
  cuda::copyToHost(counters_host, counters, 1, stream);
  FRAGG_CUDA_CHECK(cudaStreamSynchronize(stream));
  out.examine_seconds = secondsSince(t0);
  out.delta = static_cast<int64_t>(counters_host->delta);
  out.changed = counters_host->changed;
  out.examined = listed;
  return out;
}

void DeviceFrontiers::download(std::vector<BlockKey>* keys, std::vector<FrontierBits>* bits) {
  keys->clear();
  bits->clear();
  if (slots_ == 0) return;
  FRAGG_CUDA_CHECK(cudaSetDevice(scratch_->device()));
  const cudaStream_t stream = static_cast<cudaStream_t>(scratch_->stream());
  const int32_t n = slots_;
  const cuda::FrontierSlots s = slotsIn(*scratch_, n);
  BlockKey* out_keys = scratch_->device<BlockKey>(kOutKeys, n);
  FrontierBits* out_bits = scratch_->device<FrontierBits>(kOutBits, n);
  uint32_t* count = scratch_->device<uint32_t>(kOutCount, 1);
  uint32_t* count_host = scratch_->pinned<uint32_t>(kOutCountHost, 1);
  FRAGG_CUDA_CHECK(cudaMemsetAsync(count, 0, sizeof(uint32_t), stream));
  cuda::launchFrontierGather(s, out_keys, out_bits, count, stream);
  cuda::copyToHost(count_host, count, 1, stream);
  FRAGG_CUDA_CHECK(cudaStreamSynchronize(stream));
  const uint32_t m = *count_host;
  keys->resize(m);
  bits->resize(m);
  if (m == 0) return;
  cuda::copyToHost(keys->data(), out_keys, m, stream);
  cuda::copyToHost(bits->data(), out_bits, m, stream);
  FRAGG_CUDA_CHECK(cudaStreamSynchronize(stream));
}

}  // namespace fragg::planning
