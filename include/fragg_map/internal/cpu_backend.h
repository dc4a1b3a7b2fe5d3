// The CPU backend: rays in parallel over every core (OpenMP), each thread marking cells in
// its own scan scratch; the marks are merged, then the log-odds update runs over the touched
// blocks only. It works on the host map directly (its block cache is trivial).
#pragma once

#include <memory>
#include <vector>

#include "fragg_map/internal/backend.h"
#include "fragg_map/internal/prepared_scan.h"
#include "fragg_map/internal/scan_scratch.h"

namespace fragg {

class CpuBackend : public MapBackend {
 public:
  explicit CpuBackend(int threads) : threads_(threads) {}
  const char* name() const override { return "cpu"; }
  BlockCache& cache() override { return cache_; }
  bool pagesInMarkedBlocks() const override { return true; }
  const std::vector<Eigen::Vector3f>& lastDynamicPoints() const override {
    return dynamic_points_S_;
  }

 protected:
  void update(const ScanInput& scan, ScanUpdate what, const UpdateSettings& how, BlockMap& blocks,
              InsertStats& stats) override;

 private:
  /// The ray cast and update of a prepared scan.
  /// `skip_saturated`: see MapParams::skip_saturated_blocks (never used when removing).
  /// `how`: the revision and the paging hooks (UpdateSettings).
  void updatePrepared(const PreparedScan& scan, ScanUpdate what, const OccupancyModel& model,
                      RayCast raycast, bool skip_saturated, const UpdateSettings& how,
                      BlockMap& blocks, InsertStats& stats);

  int threads_;
  HostBlockCache cache_;
  std::vector<std::unique_ptr<ScanScratch>> scratch_;  // one per thread
  PreparedScan prepared_;
  std::vector<uint32_t> dynamic_rays_;             // MapParams::dynamic, last scan
  std::vector<Eigen::Vector3f> dynamic_points_S_;  // their points
  std::vector<uint64_t> surrounded_;               // MapParams::dynamic: void-to-be cells
};

}  // namespace fragg
