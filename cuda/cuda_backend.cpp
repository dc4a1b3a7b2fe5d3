#include "cuda_backend.h"

#include <algorithm>
#include <cmath>
#include <string>

#include "fragg_map/errors.h"
#include "fragg_map/internal/cuda_backend_factory.h"
#include "fragg_map/log.h"
#include "pinned_allocator.h"

namespace fragg {

std::unique_ptr<MapBackend> makeCudaBackend(const MapParams& params) {
  return std::make_unique<cuda::CudaBackend>(params);
}

namespace cuda {

namespace {
constexpr double kPi = 3.14159265358979323846;

int selectDevice(int device) {
  FRAGG_CUDA_CHECK(cudaSetDevice(device));
  return device;
}

int deviceAttribute(cudaDeviceAttr what, int device) {
  int value = 0;
  FRAGG_CUDA_CHECK(cudaDeviceGetAttribute(&value, what, device));
  return value;
}

/// Host blocks are read in place by the upload kernel when they are pinned and the device
/// addresses host memory.
bool directUploads(const MapParams& params) {
  return params.cuda.pinned_host_blocks &&
         deviceAttribute(cudaDevAttrUnifiedAddressing, params.cuda.device) != 0;
}
}  // namespace

CudaBackend::CudaBackend(const MapParams& params)
    : params_(params),
      host_allocator_(params.cuda.pinned_host_blocks ? pinnedChunkAllocator()
                                                     : plainChunkAllocator()),
      device_(selectDevice(params.cuda.device)),
      stream_(),
      cache_(stream_.get(), params.cuda.pool_max_bytes, directUploads(params),
             params.cuda.host_threads),
      integrator_(stream_.get(), cache_,
                  deviceAttribute(cudaDevAttrMultiProcessorCount, params.cuda.device),
                  params.cuda.host_threads),
      cpu_(params.threads) {}

size_t CudaBackend::deviceEstimateBytes() const {
  return size_t(estimate_blocks_) * SlotPool::bytesPerSlot();
}

void CudaBackend::sizePool(const SensorModel& model, double resolution_m) {
  if (estimate_blocks_ > 0) return;
  // The paper's formula (1)-(4) for a pinhole; the spherical shell sector for a LiDAR.
  const double block_m = resolution_m * kBlockSize;
  double blocks = 0.0;
  if (model.type == SensorType::kPinhole) {
    blocks =
        frustumVoxelEstimate(std::max(model.hfov_rad, model.vfov_rad),
                             model.max_range_m - model.min_range_m, model.min_range_m, block_m);
  } else {
    const double r = model.max_range_m, r0 = model.min_range_m;
    const double volume = 2.0 * kPi / 3.0 * (r * r * r - r0 * r0 * r0) *
                          (std::sin(model.elevation_max_rad) - std::sin(model.elevation_min_rad));
    blocks = volume / (block_m * block_m * block_m);
  }
  estimate_blocks_ = std::max<int64_t>(1, static_cast<int64_t>(std::ceil(blocks)));
  cache_.reserve(static_cast<int64_t>(std::max(4096.0, blocks * params_.cuda.pool_margin)));
}

bool CudaBackend::preparedOnHost(const PointCloud& cloud) const {
  // No-return rays need their row neighbours (DeviceScan::prepare).
  return params_.clear_no_return_rays && cloud.organised();
}

bool CudaBackend::autoSensorStats(const PointCloud& cloud, AutoSensorStats* out,
                                  bool staged_ahead) {
  if (!params_.cuda.device_auto_sensor || preparedOnHost(cloud)) return false;
  try {
    *out = integrator_.gatherAutoSensorStats(cloud, staged_ahead);
  } catch (const CudaOutOfMemory&) {
    return false;  // the scan's own upload will meet the same and fall back (Map::integrateScan)
  }
  return true;
}

void CudaBackend::update(const ScanInput& scan, ScanUpdate what, const UpdateSettings& how,
                         BlockMap& blocks, InsertStats& stats) {
  sizePool(scan.model, how.params.resolution_m);
  UpdateSettings settings = how;
  if (!params_.cuda.stage_next_cloud ||
      (settings.stage_next && preparedOnHost(*settings.stage_next)))
    settings.stage_next = nullptr;
  settings.stage_next_auto_stats =
      settings.stage_next && how.stage_next_auto_stats && params_.cuda.device_auto_sensor;
  last_on_cpu_ = false;
  if (integrator_.update(scan, what, settings, blocks, stats)) return;
  last_on_cpu_ = true;
  static bool said = false;
  if (!said) {
    logMessage(LogLevel::kWarning,
               "a scan ran on the CPU backend: its rays span more blocks than the device window "
               "table holds");
    said = true;
  }
  cache_.invalidateAll(blocks);
  if (what == ScanUpdate::kRemove)
    cpu_.remove(scan, how, blocks, stats);
  else
    cpu_.integrate(scan, how, blocks, stats);
}

}  // namespace cuda
}  // namespace fragg

namespace fragg::cuda {

bool CudaBackend::deviceView(const ViewScope& scope, BlockMap& blocks, uint64_t revision,
                             DeviceLayerView* out) {
  try {
    if (scope.keys) {
      cache_.ensureResident(*scope.keys, blocks);
      for (const BlockKey& k : *scope.keys) {
        const BlockIndex b = blocks.find(k);
        if (b != kNoBlock && cache_.slotOf(b) < 0) return false;  // evicted again: no room
      }
    } else {
      const uint64_t evicted = cache_.evictedCount();
      cache_.ensureResident(scope.lo, scope.hi, blocks);
      // Making room may have evicted blocks of the box again (only then can any be missing).
      bool host_only = false;
      if (cache_.evictedCount() != evicted)
        cache_.forEachHostOnlyIn(blocks, scope.lo, scope.hi, [&](BlockIndex) { host_only = true; });
      if (host_only) return false;
    }
  } catch (const CudaOutOfMemory&) {
    return false;  // the pool cannot hold the scope: the reader takes the host view
  }
  *out = views_.build(cache_, revision);
  return true;
}

}  // namespace fragg::cuda
