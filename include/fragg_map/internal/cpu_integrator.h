// The CPU backend: rays in parallel over every core (OpenMP), each thread marking cells in
// its own scan scratch; the marks are merged, then the log-odds update runs over the touched
// blocks only.
#pragma once

#include <memory>
#include <vector>

#include "fragg_map/internal/integrator.h"
#include "fragg_map/internal/prepared_scan.h"
#include "fragg_map/internal/scan_scratch.h"

namespace fragg {

class CpuIntegrator : public Integrator {
 public:
  explicit CpuIntegrator(int threads) : threads_(threads) {}
  void integrate(const ScanInput& scan, const MapParams& params, const OccupancyModel& model,
                 uint64_t revision, BlockMap& blocks, InsertStats& stats) override;
  /// The ray cast and update of a prepared scan (also used by the CUDA backend's fallback).
  /// `remove`: undo the scan's updates instead (no block is created).
  void integratePrepared(const PreparedScan& scan, const OccupancyModel& model, RayCast raycast,
                         uint64_t revision, BlockMap& blocks, InsertStats& stats,
                         bool remove = false);
  const char* name() const override { return "cpu"; }

 private:
  int threads_;
  std::vector<std::unique_ptr<ScanScratch>> scratch_;  // one per thread
  PreparedScan prepared_;
};

}  // namespace fragg
