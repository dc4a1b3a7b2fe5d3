// Viewpoints for frontier clusters, scored by information gain: the expected entropy reduction
// of the cells a sensor at the viewpoint would observe. Rays of the sensor model are cast from
// the viewpoint through the map (the insertion's DDA) until they reach an occupied cell or the
// maximum range; every distinct unknown cell they cross (never observed, or inside the unknown
// band) adds its entropy in bits (1 bit for a never-observed cell, H(p) for a cell in the band).
// Known cells add nothing: observing them again cannot reduce their entropy by much.
#pragma once

#include <Eigen/Core>
#include <optional>
#include <string>
#include <vector>

#include "fragg_map/map.h"
#include "fragg_map/planning/frontier_clusters.h"
#include "fragg_map/planning/query_control.h"

namespace fragg::planning {

/// The sensor a gain is computed for; its frame looks along +x rotated by the viewpoint's yaw
/// (pitch and roll zero).
struct GainSensor {
  enum class Kind { kPinhole, kLidar };
  Kind kind = Kind::kPinhole;
  /// Rays: pinhole, columns x rows over the field of view; LiDAR, azimuths (full turn) x
  /// elevations.
  int columns = 64, rows = 48;
  double horizontal_fov_rad = 1.5708, vertical_fov_rad = 1.2;      ///< pinhole, (0, pi)
  double min_elevation_rad = -0.2618, max_elevation_rad = 0.2618;  ///< LiDAR
  double max_range_m = 10.0;
  /// Throws InvalidArgument naming the bad field.
  void validate() const;
};

/// Entropy gain (bits) of the sensor at `position_m` with `yaw_rad`. Hold the map's read lock.
double viewpointGainBits(const Map& map, const BlockView& view, const Eigen::Vector3d& position_m,
                         double yaw_rad, const GainSensor& sensor);

/// The CUDA kernels for a batch of entropy gains (viewpointGainsBits on a map integrating on
/// CUDA). All walk the same cells as the CPU (the same gains, to rounding); they differ in how
/// a viewpoint's seen cells are kept (each unknown cell counts once a viewpoint) and in how
/// rays are handed to threads.
enum class GainKernel {
  /// One thread a ray; a dense cell bitmap a viewpoint, every one the size of the largest
  /// viewpoint's box (the tested default).
  kPlain,
  /// As kPlain, each viewpoint's bitmap the size of its own box (less to clear).
  kSized,
  /// One thread a ray; seen cells by map block: a viewpoint has a directory over its box's
  /// blocks, and the first lane meeting an unknown cell in a block takes a 64-byte bitmap for
  /// it from a pool shared by the round (and clears it): only the directories are cleared.
  /// Viewpoints of a round that finds the pool too small are computed again by kSized.
  kPooled,
  /// Persistent threads on kSized's bitmaps: a warp whose rays have ended takes the next rays
  /// from a queue (one atomic a warp), so lanes keep walking instead of waiting for the
  /// warp's longest ray.
  kQueued,
  /// kQueued's scheduling with kPooled's bitmaps.
  kPooledQueued,
  /// kPooledQueued whose walk sets seen bits without waiting for the atomics' old values (no
  /// cell read while walking); a second kernel sums the entropy of the cells set in each
  /// taken pool bitmap into its viewpoint's gain.
  kDeferred,
  /// kDeferred without the queue: kPooled's one thread a ray, setting seen bits without
  /// waiting (the atomics' latency off the walk), then the same sum pass.
  kPooledDeferred,
};

/// Whether `kernel` keeps seen cells in block bitmaps from a pool (kPooled, kPooledQueued,
/// kDeferred, kPooledDeferred).
[[nodiscard]] bool gainKernelPooled(GainKernel kernel);
/// Whether `kernel` hands rays out from a queue (kQueued, kPooledQueued, kDeferred).
[[nodiscard]] bool gainKernelQueued(GainKernel kernel);
/// Whether `kernel` sets seen bits without reading them and sums gains in a second pass
/// (kDeferred, kPooledDeferred).
[[nodiscard]] bool gainKernelDeferred(GainKernel kernel);

/// Every GainKernel, kPlain first.
inline constexpr GainKernel kGainKernels[] = {GainKernel::kPlain,         GainKernel::kSized,
                                              GainKernel::kPooled,        GainKernel::kQueued,
                                              GainKernel::kPooledQueued,  GainKernel::kDeferred,
                                              GainKernel::kPooledDeferred};

/// "plain", "sized", "pooled", "queued", "pooled-queued", "deferred" or "pooled-deferred".
[[nodiscard]] const char* gainKernelName(GainKernel kernel);
/// The kernel named `name` (gainKernelName's names); InvalidArgument for another name.
[[nodiscard]] GainKernel gainKernelFromName(const std::string& name);

/// How a batch of gains runs on the device (ignored on the CPU).
struct GainDeviceOptions {
  GainKernel kernel = GainKernel::kPlain;
  /// Pooled kernels (gainKernelPooled): block bitmaps in the pool (64 bytes each); 0 sizes the pool
  /// from the bitmap budget (three quarters of it), never larger than a round's directories
  /// (one bitmap for every block of every box: a pool that cannot run out).
  size_t pool_blocks = 0;
  /// Queued kernels (gainKernelQueued): a warp takes new rays once at least this many of its 32
  /// lanes have finished theirs (1..32).
  int refill_lanes = 4;
  /// Device bytes for one round's bitmaps (every kernel; the pooled kernels give a quarter to
  /// the directories, the rest to the pool unless pool_blocks says); a batch whose bitmaps pass
  /// it runs in several rounds. 0: a quarter of the device's free memory, within 1 to 4 GiB.
  size_t bitmap_budget_bytes = 0;
  /// Throws InvalidArgument naming the bad field.
  void validate() const;
};

/// Where a batch of gains spent its time on the device (viewpointGainsBits with `timings`;
/// all zero when the batch ran on the CPU): the map's device view over the batch's reach
/// (residency and its block table), the batch's own tables (inputs copied, the dense block
/// table, the cell bitmaps cleared) and the walk kernels with the gains copied back, seconds.
/// Timing adds a stream synchronisation between the stages.
struct GainTimings {
  bool on_device = false;
  double view_seconds = 0.0, tables_seconds = 0.0, walk_seconds = 0.0;
  size_t rounds = 0;  ///< kernel launches (bitmaps of one round fit the device budget)
  /// Pooled kernels: the most block bitmaps one round asked the pool for (its demand, which
  /// may pass the pool), and the viewpoints computed again by kSized after their round found
  /// the pool too small.
  size_t pool_blocks_wanted = 0, pool_reruns = 0;
};

/// Gains of many viewpoints at once; result i belongs to position i and yaw i (the two must
/// have the same length). `backend`: kCpu walks the host blocks (OpenMP, `threads` 0 = every
/// core); kAuto uses the map's backend where it has a gain path (a map integrating on CUDA:
/// one device thread per ray over its block cache, the same cells as the CPU walk; sums equal
/// to rounding), else the CPU, falling back to the CPU with one log line when the device
/// cannot take the batch; kCuda insists (InvalidArgument for a map not on CUDA). `device`:
/// the kernel on CUDA. `timings` (optional): where the device's time went.
std::vector<double> viewpointGainsBits(const Map& map,
                                       const std::vector<Eigen::Vector3d>& positions_m,
                                       const std::vector<double>& yaws_rad,
                                       const GainSensor& sensor, int threads = 0,
                                       Backend backend = Backend::kCpu,
                                       const GainDeviceOptions& device = {},
                                       GainTimings* timings = nullptr);

/// Entropy (bits) of a cell as the gain counts it: 1 for never observed, H(p) inside the
/// unknown band, 0 for free and occupied cells.
double cellEntropyBits(const Map& map, const Cell* cell);

/// What a viewpoint's gain counts.
enum class ViewpointGain {
  /// The expected entropy reduction (bits) of the unknown cells the sensor's rays cross, the
  /// paper's gain (viewpointGainsBits): every ray walked to its end, so its cost grows with the
  /// rays, the range and 1 / resolution.
  kEntropy,
  /// Coverage, as FUEL ranks viewpoints: the number of the cluster's own frontier cells the
  /// sensor would see, i.e. within its range and field of view with every cell between the
  /// viewpoint and the cell free (an occupied or unknown cell hides it). One short walk per
  /// cluster cell: cheap enough for thousands of clusters of a LiDAR map.
  kCoverage,
};

/// "entropy" or "coverage" (the names the CLI and the node take).
[[nodiscard]] const char* viewpointGainName(ViewpointGain gain);
/// The gain named `name` ("entropy" | "coverage"); InvalidArgument for another name.
[[nodiscard]] ViewpointGain viewpointGainFromName(const std::string& name);

struct ViewpointOptions {
  std::vector<double> radii_m = {1.5, 3.0};  ///< ring radii around the cluster centroid, > 0
  int angles = 12;                           ///< candidates per ring, >= 1
  std::vector<double> heights_m = {0.0};     ///< offsets from the centroid's z
  /// > 0: the candidate must be free with no occupied or unknown cell within this radius
  /// (a sphere collision check with unknown cells as obstacles); 0: its own cell free.
  double clearance_m = 0.3;
  int top_k = 3;  ///< >= 1
  GainSensor sensor;
  /// Where the gains are computed (viewpointGainsBits): kAuto follows the map's backend.
  Backend backend = Backend::kAuto;
  /// The kernel when they are computed on CUDA.
  GainDeviceOptions device_gains;
  /// What the gain counts; kCoverage is always computed on the host.
  ViewpointGain gain = ViewpointGain::kEntropy;
  /// Ranks by gain per metre of straight-line distance from this position (else by gain).
  std::optional<Eigen::Vector3d> robot_m;
  /// Throws InvalidArgument naming the bad field.
  void validate() const;
};

struct Viewpoint {
  Eigen::Vector3d position_m = Eigen::Vector3d::Zero();
  double yaw_rad = 0.0;  ///< facing the cluster centroid
  /// The gain: entropy bits (ViewpointGain::kEntropy) or frontier cells seen (kCoverage).
  double gain_bits = 0.0;
  double distance_m = 0.0;  ///< from the robot (0 without one)
  double score = 0.0;       ///< gain, or gain per metre with a robot position
};

/// How far from a cluster's cells its viewpoints look into the map (m): the farthest ring
/// candidate from the centroid plus the clearance sphere, plus the sensor's range for the
/// entropy gain (coverage walks only towards the cluster's own cells).
[[nodiscard]] double viewpointReachM(const ViewpointOptions& options);

/// The coverage gain (ViewpointGain::kCoverage) of the sensor at `position_m` with `yaw_rad`:
/// how many of `cluster`'s cells it sees. Hold the map's read lock.
[[nodiscard]] double coverageGainCells(const Map& map, const BlockView& view,
                                       const FrontierCluster& cluster,
                                       const Eigen::Vector3d& position_m, double yaw_rad,
                                       const GainSensor& sensor);

/// The best `top_k` viewpoints of a cluster (highest score first; candidates with zero gain
/// are dropped). Hold the map's read lock.
[[nodiscard]] std::vector<Viewpoint> clusterViewpoints(const Map& map,
                                                       const FrontierCluster& cluster,
                                                       const ViewpointOptions& options);

/// clusterViewpoints for every cluster at once (element i belongs to cluster i, equal to
/// clusterViewpoints(map, clusters[i], options)): the candidates of all clusters share one
/// clearance batch and one gain batch (`threads` CPU threads, 0 = every core). `control`:
/// QueryStopped when it fires (checked between the steps and every few hundred candidates).
/// Hold the map's read lock.
[[nodiscard]] std::vector<std::vector<Viewpoint>> clustersViewpoints(
    const Map& map, const std::vector<FrontierCluster>& clusters, const ViewpointOptions& options,
    int threads = 0, const QueryControl* control = nullptr);

}  // namespace fragg::planning
