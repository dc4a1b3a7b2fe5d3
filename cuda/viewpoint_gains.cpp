#include "viewpoint_gains.h"

#include <algorithm>
#include <cmath>
#include <string>

#include "cuda_stream.h"
#include "fragg_map/errors.h"

namespace fragg::cuda {

namespace {

/// Device memory for the bitmaps of one round of viewpoints.
constexpr uint64_t kSeenBudgetBytes = uint64_t(1) << 30;
constexpr uint64_t kMaxSeenBytesPerViewpoint = uint64_t(4) << 30;

uint64_t tableSizeFor(int64_t n) {
  uint64_t size = 1024;
  while (size < uint64_t(2 * n)) size *= 2;
  return size;
}

}  // namespace

void ViewpointGains::compute(DeviceBlockCache& cache, const GainBatch& batch,
                             const OccupancyModel& model, BlockMap& blocks, double* out) {
  const size_t n = batch.viewpoints();
  if (n == 0) return;
  const int half = static_cast<int>(std::ceil(batch.length_v)) + 2;
  const uint64_t side = uint64_t(2 * half + 1);
  const uint64_t words = (side * side * side + 63) / 64;
  if (words * 8 > kMaxSeenBytesPerViewpoint)
    throw InvalidArgument("gain range too long for the device (a viewpoint's cell bitmap of " +
                          std::to_string(words * 8 >> 20) + " MiB)");
  // Every block a ray can reach, resident.
  double lo[3], hi[3];
  for (int a = 0; a < 3; ++a) {
    lo[a] = hi[a] = batch.origins_v[a];
    for (size_t i = 0; i < n; ++i) {
      lo[a] = std::min(lo[a], batch.origins_v[3 * i + a]);
      hi[a] = std::max(hi[a], batch.origins_v[3 * i + a]);
    }
  }
  const auto blockOf = [&](double v) { return static_cast<int>(std::floor(v)) >> kBlockBits; };
  const BlockKey box_lo{blockOf(lo[0] - half), blockOf(lo[1] - half), blockOf(lo[2] - half)};
  const BlockKey box_hi{blockOf(hi[0] + half), blockOf(hi[1] + half), blockOf(hi[2] + half)};
  cache.ensureResident(box_lo, box_hi, blocks);
  size_t host_only = 0;
  cache.forEachHostOnlyIn(blocks, box_lo, box_hi, [&](BlockIndex) { ++host_only; });
  if (host_only)
    throw CudaOutOfMemory("device block pool cannot hold the " + std::to_string(host_only) +
                          " more blocks the viewpoints' rays reach");
  // Block key -> slot over the resident pool.
  const SlotArrays slots = cache.arrays();
  const uint64_t table_size = tableSizeFor(slots.capacity - cache.freeSlots());
  table_keys_.reserve(table_size);
  table_slots_.reserve(table_size);
  FRAGG_CUDA_CHECK(cudaMemsetAsync(table_keys_.get(), 0xff, table_size * 8, stream_));
  launchBlockTableBuild(slots, table_keys_.get(), table_slots_.get(), table_size - 1, stream_);
  // Viewpoints and rays.
  const size_t n_rays = batch.rays();
  origins_.reserve(3 * n);
  cos_.reserve(n);
  sin_.reserve(n);
  rays_.reserve(3 * n_rays);
  gains_.reserve(n);
  copyToDevice(origins_.get(), batch.origins_v.data(), 3 * n, stream_);
  copyToDevice(cos_.get(), batch.cos_yaw.data(), n, stream_);
  copyToDevice(sin_.get(), batch.sin_yaw.data(), n, stream_);
  copyToDevice(rays_.get(), batch.rays_sensor.data(), 3 * n_rays, stream_);
  FRAGG_CUDA_CHECK(cudaMemsetAsync(gains_.get(), 0, n * sizeof(double), stream_));
  const size_t per_round = std::max<size_t>(1, std::min<size_t>(n, kSeenBudgetBytes / (words * 8)));
  seen_.reserve(per_round * words);
  for (size_t first = 0; first < n; first += per_round) {
    const size_t m = std::min(per_round, n - first);
    FRAGG_CUDA_CHECK(cudaMemsetAsync(seen_.get(), 0, m * words * 8, stream_));
    GainKernelArgs args{table_keys_.get(),
                        table_slots_.get(),
                        table_size - 1,
                        slots.cells,
                        model,
                        origins_.get() + 3 * first,
                        cos_.get() + first,
                        sin_.get() + first,
                        rays_.get(),
                        static_cast<uint32_t>(n_rays),
                        static_cast<uint32_t>(m),
                        batch.length_v,
                        half,
                        words,
                        seen_.get(),
                        gains_.get() + first};
    launchViewpointGains(args, stream_);
  }
  copyToHost(out, gains_.get(), n, stream_);
  FRAGG_CUDA_CHECK(cudaStreamSynchronize(stream_));
}

}  // namespace fragg::cuda
