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
#include "state_bits.h"
#include "viewpoint_gains.h"

namespace fragg::cuda {

class CudaBackend : public MapBackend {
 public:
  explicit CudaBackend(const MapParams& params);

  const char* name() const override { return "cuda"; }
  BlockCache& cache() override { return cache_; }
  bool cullsOnItsOwn() const override { return true; }
  size_t deviceBytes() const override { return cache_.deviceBytes() + integrator_.deviceBytes(); }
  size_t deviceEstimateBytes() const override;
  std::shared_ptr<ChunkAllocator> hostAllocator() const override { return host_allocator_; }
  bool cellStateBits(const std::vector<BlockKey>& keys, const OccupancyModel& model,
                     BlockMap& blocks, uint64_t* out) override {
    state_bits_.compute(cache_, keys, model, blocks, out);
    return true;
  }
  /// On the device beside the points' upload, which the scan's prepare then reuses; false
  /// (the map gathers on the host) for a cloud prepared on the host, and when the device has
  /// no room for the points.
  bool autoSensorStats(const PointCloud& cloud, AutoSensorStats* out, bool staged_ahead) override;
  bool viewpointGains(const GainBatch& batch, const OccupancyModel& model, BlockMap& blocks,
                      double* out) override {
    gains_.compute(cache_, batch, model, blocks, out);
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
  CellStateBits state_bits_{stream_.get()};
  ViewpointGains gains_{stream_.get()};
  int64_t estimate_blocks_ = 0;
};

}  // namespace fragg::cuda
