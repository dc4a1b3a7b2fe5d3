// Every parameter of a map, with its default. The one place defaults live.
#pragma once

#include <cstddef>
#include <limits>
#include <string>

#include "fragg_map/occupancy.h"

namespace fragg {

enum class Backend : uint8_t { kAuto = 0, kCpu = 1, kCuda = 2 };
const char* toString(Backend b);
Backend backendFromString(const std::string& s);  ///< "auto" | "cpu" | "cuda"

/// kDda: exact DDA in voxel units relative to the sensor (precise anywhere on an int32 map);
/// kBresenham: 26-connected lines; kOctomap: liboctomap's computeRayKeys arithmetic step for
/// step (float metres, raycast_octomap.h), so that the cells match OctoMap's at long range.
enum class RayCast : uint8_t { kDda = 0, kBresenham = 1, kOctomap = 2 };
const char* toString(RayCast r);
RayCast rayCastFromString(const std::string& s);  ///< "dda" | "bresenham" | "octomap"

struct CullingParams {
  bool plane_memory = true;           ///< test the plane that rejected a block last time first
  bool rotation_coherence = true;     ///< skip re-testing blocks rejected within the TTL
  bool translation_coherence = true;  ///< skip re-testing near-plane rejects after moving ahead
  int coherence_ttl_scans = 8;        ///< how long a rejection may be reused
};

/// The CUDA backend's knobs (ignored by the CPU backend).
struct CudaParams {
  int device = 0;
  /// Initial device pool, as a multiple of the sensor's frustum volume in blocks (the paper's
  /// formula (1)-(4)); the pool grows when a scan needs more, up to `pool_max_bytes`.
  double pool_margin = 1.5;
  /// Most device memory the block pool may take; 0 = half of the device's free memory. When
  /// the pool is full, least recently visible blocks are evicted to the host.
  size_t pool_max_bytes = 0;
  /// Host blocks in pinned memory (off: pageable, for the ablation).
  bool pinned_host_blocks = true;
  /// Rays read through the read-only data cache (off: plain loads, for the ablation).
  bool readonly_ray_loads = true;
  /// A ray gathers its marks of one scratch word before issuing them (one filter look-up and
  /// one atomic per word; off: per cell, for the ablation). The map is the same either way.
  bool coalesce_ray_marks = true;
  /// An `auto` sensor model's statistics are gathered on the device beside the points' upload
  /// (off: on the host, for the ablation). The model is the same either way.
  bool device_auto_sensor = true;
  /// The apply kernel updates each touched block with one warp (off: one thread block of 128
  /// threads, for the ablation). The map is the same either way.
  bool warp_per_slot_apply = true;
  /// In a batch (Map::insertSequence, Map::correctPoses) the next cloud is copied into pinned
  /// memory while the device ray casts the current one, then uploaded behind it (off: each
  /// scan uploads its own, for the ablation). The map is the same either way.
  bool stage_next_cloud = true;
  /// > 0: the ray pass cuts each ray into pieces of this many cells along its major axis and
  /// a thread block's threads share its rays' pieces, so that a warp does not wait for its
  /// longest ray (0: one thread a ray, for the ablation). DDA only; the map is the same.
  /// 192: W1 at 50 m 7 % faster, 30 m and W2 unchanged; pieces of 8-64 cells were slower
  /// (docs/benchmarks.md).
  int ray_piece_steps = 192;
  /// Threads of the backend's host-side copies (a scan's points into pinned staging, blocks
  /// to and from the device); 0 = every core. With every core, single scans on a 16-core host
  /// took 3-7 ms instead of 1-2 (most likely waiting for the last thread to wake); 4 threads
  /// cost 0.03-0.05 ms of median (docs/benchmarks.md, p99).
  int host_threads = 4;
};

/// The scan store for loop-closure correction (see scan_store.h).
struct ScanStoreParams {
  bool keep = false;  ///< keep every inserted scan (remove / correctPoses need it)
  /// 0 (default): kept points are float32, exactly as received, so the map integrates the
  /// received cloud (the same map as without keeping, and as OctoMap's). > 0: a memory option:
  /// points are quantised to int16 at this step (6 bytes a point instead of 12) and the map
  /// integrates the quantised points, so endpoints near a cell face can change cell and long
  /// rays their path (at 1 mm and 5 cm cells, 0.2-1.2 % of the cells differ from the map of
  /// the received points on real RGB-D and Velodyne scans).
  double point_step_m = 0.0;
  size_t max_bytes = 0;   ///< points kept in memory at most; 0 = no limit
  std::string spill_dir;  ///< where points beyond max_bytes go; empty: they are dropped
};

/// Points dropped before integration by their height in the map frame (octomap_server's
/// pointcloud_min_z / pointcloud_max_z): a point whose map-frame z lies outside
/// [min_z_m, max_z_m] is not inserted (InsertStats::dropped_height). Default: every height.
struct HeightFilterParams {
  double min_z_m = -std::numeric_limits<double>::infinity();
  double max_z_m = std::numeric_limits<double>::infinity();

  /// False when the band keeps every height.
  bool active() const {
    return min_z_m > -std::numeric_limits<double>::infinity() ||
           max_z_m < std::numeric_limits<double>::infinity();
  }
};

/// How MapParams::dynamic makes space void (DESIGN §12).
enum class VoidSpaceRule {
  /// main's rule (the default): a cell is void when observed free with confidence
  /// (probability <= void_probability); a hit there is dynamic when every neighbour within
  /// known_radius_cells has been observed; a ray passing through an occupied cell whose
  /// neighbourhood has been observed makes it void at once.
  kPassThrough,
  /// DUFOMap's surround test: a cell a scan's rays pass through (none ending there) becomes
  /// void (the lower clamp) when no neighbour within known_radius_cells is unknown or hit by
  /// the same scan (occupied cells left by earlier hits do not count against it); an ordinary
  /// miss stops one unit above the clamp.
  kSurround,
};

/// The rule's name as the CLI spells it ("pass-through", "surround").
[[nodiscard]] const char* toString(VoidSpaceRule rule);
/// The rule named `name` ("pass-through" or "surround"); throws InvalidArgument otherwise.
[[nodiscard]] VoidSpaceRule voidSpaceRuleFromString(const std::string& name);

/// Dynamic scenes (DESIGN §12), off by default (OctoMap's rule unchanged). When enabled, each
/// scan's hits are classified against the map as it was before the scan: a hit in void space
/// (see `rule`) is dynamic: it is not inserted, its ray clears up to it as a free-only ray
/// would (the hit's own cell is left as it was), and it is counted (InsertStats::rays_dynamic)
/// and handed back (Map's last dynamic points). Under kPassThrough (the default) a hit is
/// dynamic when its cell is observed free with confidence (probability <= void_probability)
/// and every neighbour within known_radius_cells (Chebyshev) has been observed, and a ray
/// passing through an occupied cell whose neighbourhood has been observed makes it void at
/// once (what stood there has moved) instead of taking one miss. Under kSurround space becomes
/// void by DUFOMap's surround test (VoidSpaceRule::kSurround); a hit is dynamic in a void cell
/// or in a cell free with confidence whose every neighbour is too. Either way a static surface
/// keeps unseen or hit cells around it (the ground's below it, a wall's inside), as DUFOMap's
/// unknown inflation does. Blocks that are paged out read as unobserved.
struct DynamicParams {
  bool enabled = false;
  /// How space becomes void; kPassThrough (main's rule) unless chosen.
  VoidSpaceRule rule = VoidSpaceRule::kPassThrough;
  /// Free with confidence at or below this occupancy probability (kPassThrough: void); in
  /// (0, 0.5 - unknown band), and at least occupancy.clamp_min.
  double void_probability = 0.25;
  /// The neighbourhood's Chebyshev radius (cells): 0 to 2.
  int known_radius_cells = 2;
  /// Forgetting, off at 0 (the default; independent of `enabled`): after each integrated scan
  /// every observed cell's log-odds moves this much toward 0 (probability 0.5), stopping at 0,
  /// so that what is not seen again fades into the unknown band (a person who stood still
  /// long enough to be mapped, a parked car that left unseen). In [0, 4] (log-odds per scan;
  /// 4 takes a cell from either clamp to 0 in one scan). A map-wide pass over the host map:
  /// the CPU backend only (backend cuda is refused, auto takes the CPU), not with scans.keep,
  /// not with a page store (its blocks would miss the scans they were paged out for). Void
  /// cells (either rule) fade like the others: they stop being void after one scan.
  double decay_log_odds_per_scan = 0.0;
};

struct MapParams {
  double resolution_m = 0.05;
  OccupancyParams occupancy;
  Backend backend = Backend::kAuto;
  RayCast raycast = RayCast::kDda;
  /// Rays of organised clouds without a return clear free space up to the max range.
  bool clear_no_return_rays = false;
  /// A ray cut at the sensor's max range also frees the cell at the cut point, as
  /// octomap_server's insertScan does (off: liboctomap's insertPointCloud, which leaves that
  /// cell as it was). Ground and other free-only points keep their end cell either way.
  bool free_cut_cell = false;
  /// The ray pass walks past blocks whose every cell sits at the lower clamp without visiting
  /// their cells (a miss changes nothing there: the map is the same either way). Off only to
  /// measure what it saves.
  bool skip_saturated_blocks = true;
  CullingParams culling;
  /// Worker threads for the CPU backend; 0 = every core.
  int threads = 0;
  CudaParams cuda;
  ScanStoreParams scans;
  HeightFilterParams height_filter;
  DynamicParams dynamic;

  /// Throws InvalidArgument naming the bad field.
  void validate() const;
};

}  // namespace fragg
