#include "viewpoint_gains.h"

#include <algorithm>
#include <cmath>
#include <string>

#include "cuda_check.h"
#include "cuda_stream.h"
#include "fragg_map/errors.h"
#include "gain_kernels.h"

namespace fragg::planning {

namespace {

/// Device memory for the bitmaps of one round of viewpoints.
constexpr uint64_t kSeenBudgetBytes = uint64_t(1) << 30;
constexpr uint64_t kMaxSeenBytesPerViewpoint = uint64_t(4) << 30;

/// The walk's buffers in the scratch (device buffer ids).
enum Buffer : int { kOrigins = 200, kCos, kSin, kRays, kGains, kSeen };

/// Half the side of a viewpoint's cell bitmap cube.
int halfSideOf(const GainBatch& batch) { return static_cast<int>(std::ceil(batch.length_v)) + 2; }

}  // namespace

void gainReach(const GainBatch& batch, BlockKey* lo_key, BlockKey* hi_key) {
  const size_t n = batch.viewpoints();
  const int half = halfSideOf(batch);
  double lo[3], hi[3];
  for (int a = 0; a < 3; ++a) {
    lo[a] = hi[a] = n ? batch.origins_v[a] : 0.0;
    for (size_t i = 0; i < n; ++i) {
      lo[a] = std::min(lo[a], batch.origins_v[3 * i + a]);
      hi[a] = std::max(hi[a], batch.origins_v[3 * i + a]);
    }
  }
  const auto blockOf = [&](double v) { return static_cast<int>(std::floor(v)) >> kBlockBits; };
  *lo_key = BlockKey{blockOf(lo[0] - half), blockOf(lo[1] - half), blockOf(lo[2] - half)};
  *hi_key = BlockKey{blockOf(hi[0] + half), blockOf(hi[1] + half), blockOf(hi[2] + half)};
}

void viewpointGainsOnDevice(const DeviceLayerView& view, DeviceScratch& scratch,
                            const GainBatch& batch, const OccupancyModel& model, double* out) {
  const size_t n = batch.viewpoints();
  if (n == 0) return;
  const int half = halfSideOf(batch);
  const uint64_t side = uint64_t(2 * half + 1);
  const uint64_t words = (side * side * side + 63) / 64;
  if (words * 8 > kMaxSeenBytesPerViewpoint)
    throw InvalidArgument("gain range too long for the device (a viewpoint's cell bitmap of " +
                          std::to_string(words * 8 >> 20) + " MiB)");
  FRAGG_CUDA_CHECK(cudaSetDevice(scratch.device()));
  const cudaStream_t stream = static_cast<cudaStream_t>(scratch.stream());
  const size_t n_rays = batch.rays();
  double* origins = scratch.device<double>(kOrigins, 3 * n);
  double* cos_yaw = scratch.device<double>(kCos, n);
  double* sin_yaw = scratch.device<double>(kSin, n);
  double* rays = scratch.device<double>(kRays, 3 * n_rays);
  double* gains = scratch.device<double>(kGains, n);
  cuda::copyToDevice(origins, batch.origins_v.data(), 3 * n, stream);
  cuda::copyToDevice(cos_yaw, batch.cos_yaw.data(), n, stream);
  cuda::copyToDevice(sin_yaw, batch.sin_yaw.data(), n, stream);
  cuda::copyToDevice(rays, batch.rays_sensor.data(), 3 * n_rays, stream);
  FRAGG_CUDA_CHECK(cudaMemsetAsync(gains, 0, n * sizeof(double), stream));
  const size_t per_round = std::max<size_t>(1, std::min<size_t>(n, kSeenBudgetBytes / (words * 8)));
  unsigned long long* seen = scratch.device<unsigned long long>(kSeen, per_round * words);
  for (size_t first = 0; first < n; first += per_round) {
    const size_t m = std::min(per_round, n - first);
    FRAGG_CUDA_CHECK(cudaMemsetAsync(seen, 0, m * words * 8, stream));
    cuda::GainKernelArgs args{view,
                              model,
                              origins + 3 * first,
                              cos_yaw + first,
                              sin_yaw + first,
                              rays,
                              static_cast<uint32_t>(n_rays),
                              static_cast<uint32_t>(m),
                              batch.length_v,
                              half,
                              words,
                              seen,
                              gains + first};
    cuda::launchViewpointGains(args, stream);
  }
  cuda::copyToHost(out, gains, n, stream);
  FRAGG_CUDA_CHECK(cudaStreamSynchronize(stream));
}

}  // namespace fragg::planning
