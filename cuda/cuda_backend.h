// The CUDA backend (DESIGN §3, §11): the host map stays the map; a device block cache holds
// the blocks scans need (write-back); the integrator runs each scan on the device. A scan
// whose rays span more blocks than the window table holds runs on the CPU backend instead.
#pragma once

#include <memory>

#include "cuda_integrator.h"
#include "cuda_stream.h"
#include "device_block_cache.h"
#include "fragg_map/internal/backend.h"
#include "fragg_map/internal/cpu_backend.h"
#include "layer_view.h"

namespace fragg::cuda {

class CudaBackend : public MapBackend {
 public:
  explicit CudaBackend(const MapParams& params);

  const char* name() const override { return "cuda"; }
  BlockCache& cache() override { return cache_; }
  bool cullsOnItsOwn() const override { return true; }
  /// Paging: its rays report the paged-out blocks they reach (UpdateSettings::device_paging).
  bool reportsReachedBlocks() const override { return true; }
  size_t deviceBytes() const override {
    return cache_.deviceBytes() + integrator_.deviceBytes() + views_.deviceBytes() +
           (scratch_ ? scratch_->deviceBytes() : 0);
  }
  size_t deviceEstimateBytes() const override;
  std::shared_ptr<ChunkAllocator> hostAllocator() const override { return host_allocator_; }
  /// On the device beside the points' upload, which the scan's prepare then reuses; false
  /// (the map gathers on the host) for a cloud prepared on the host, and when the device has
  /// no room for the points.
  bool autoSensorStats(const PointCloud& cloud, AutoSensorStats* out, bool staged_ahead) override;
  /// The view over the device pool once the scope's host blocks are resident; false when the
  /// pool cannot hold them all at once.
  bool deviceView(const ViewScope& scope, BlockMap& blocks, uint64_t revision,
                  DeviceLayerView* out) override;
  DeviceScratch* deviceScratch() override {
    if (!scratch_) scratch_ = makeDeviceScratch(device_);
    return scratch_.get();
  }
  /// MapParams::dynamic: classified on the device (or by the CPU backend for a scan that ran
  /// there).
  const std::vector<Eigen::Vector3f>& lastDynamicPoints() const override {
    return last_on_cpu_ ? cpu_.lastDynamicPoints() : integrator_.lastDynamicPoints();
  }
  bool masksChangedSince(uint64_t revision, std::vector<BlockKey>* keys,
                         std::vector<BlockStateMasks>* masks) override {
    views_.masksChangedSince(cache_, revision, keys, masks);
    return true;
  }

 protected:
  void update(const ScanInput& scan, ScanUpdate what, const UpdateSettings& how, BlockMap& blocks,
              InsertStats& stats) override;

 private:
  /// Whether the cloud's rays are prepared on the host (no staging, no device statistics).
  bool preparedOnHost(const PointCloud& cloud) const;
  /// Sizes the pool on the first scan from the sensor's visible volume.
  void sizePool(const SensorModel& model, double resolution_m);

  MapParams params_;
  std::shared_ptr<ChunkAllocator> host_allocator_;
  int device_;  ///< selected before the stream is made
  CudaStream stream_;
  DeviceBlockCache cache_;
  CudaIntegrator integrator_;
  CpuBackend cpu_;  ///< for scans whose window would not fit
  LayerViews views_{stream_.get(), device_};
  std::unique_ptr<DeviceScratch> scratch_;  ///< readers' buffers (planning), made when asked
  int64_t estimate_blocks_ = 0;
  bool last_on_cpu_ = false;  ///< the last scan ran on cpu_ (its dynamic points are there)
};

}  // namespace fragg::cuda
