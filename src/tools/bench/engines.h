// Timed runs of one workload through one engine: fragg with a given backend (the map params'
// `backend`, so a CUDA column is one more value) or OctoMap's insertPointCloud.
#pragma once

#include <cstdint>
#include <string>
#include <vector>

#include "bench/workloads.h"
#include "fragg_map/map.h"

namespace fragg::bench {

struct Figures {
  std::vector<double> ms;               ///< per scan (all repeats)
  std::vector<InsertStats> scan_stats;  ///< per scan (all repeats), beside `ms`
  uint64_t visits = 0;                  ///< fragg: cell visits of the traversal
  double seconds = 0;
  size_t known = 0;                                    ///< known voxels of the last run's map
  size_t bytes = 0;                                    ///< host bytes of the last run's map
  size_t device_bytes = 0, device_estimate_bytes = 0;  ///< CUDA: in use / formula (1)
  InsertStats totals;                                  ///< summed over the last run
};

/// An engine name: a backend, then options joined by '+': cpu, cuda, cuda+pageable (host
/// blocks in pageable memory), cuda+plain-loads (no read-only cache path for rays),
/// cuda+no-coherence (frustum coherence off), cuda+bresenham, cpu+octomap-raycast /
/// cuda+octomap-raycast (RayCast::kOctomap: computeRayKeys's arithmetic), cpu+no-skip /
/// cuda+no-skip (the ray pass visits blocks at the lower clamp too), cuda+no-coalesce (a ray's
/// marks issued per cell, not per scratch word), cuda+host-auto (the auto sensor model's statistics
/// gathered on the host), cuda+block-apply (the apply kernel updates a block with a thread block,
/// not a warp), cuda+no-staging (no next cloud staged in a batch), cuda+pieces=N (rays cut into
/// pieces of N cells of their major axis; 0: one thread a ray), +sequence (the scans inserted by
/// one Map::insertSequence call, each scan's time its InsertStats::seconds_total; the map params
/// are the backend's). Throws InvalidArgument.
MapParams engineParams(const std::string& engine, const MapParams& base);

/// Inserts the first `count` scans into an empty map `repeats` times; the last map is moved
/// into `keep` when given. unknown_band 0 (OctoMap's rule, for agreement figures).
Figures runFragg(const Workload& w, const std::string& engine, size_t count, int repeats,
                 int threads, Map* keep);

#ifdef FRAGG_HAVE_OCTOMAP
struct OctomapRun {
  Figures figures;
  Map map;  ///< OctoMap's tree as a map (coarse leaves expanded), for agreement figures
};
OctomapRun runOctomap(const Workload& w, size_t count);

/// Cell agreement of a fragg map with OctoMap's, OctoMap's rule on both sides: among cells
/// both know, and among cells either knows.
std::pair<double, double> agreementWithOctomap(const Map& fragg_map, const Map& octomap_map);
#endif

}  // namespace fragg::bench
