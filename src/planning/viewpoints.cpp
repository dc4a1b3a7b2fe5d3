#include "fragg_map/planning/viewpoints.h"

#include <fmt/format.h>
#include <omp.h>

#include <algorithm>
#include <chrono>
#include <cmath>
#include <string>
#include <unordered_set>

#include "fragg_map/errors.h"
#include "fragg_map/internal/seconds_since.h"
#include "gain_walk.h"
#if FRAGG_HAVE_CUDA
#include "cuda/viewpoint_gains.h"
#endif
#include "fragg_map/internal/thread_count.h"
#include "fragg_map/log.h"
#include "fragg_map/planning/collision_check.h"

namespace fragg::planning {

namespace {

constexpr double kPi = 3.14159265358979323846;

// Unit ray directions of the sensor in its own frame (x forward, z up).
std::vector<Eigen::Vector3d> sensorRays(const GainSensor& s) {
  std::vector<Eigen::Vector3d> rays;
  rays.reserve(size_t(s.columns) * size_t(s.rows));
  for (int r = 0; r < s.rows; ++r)
    for (int c = 0; c < s.columns; ++c) {
      if (s.kind == GainSensor::Kind::kPinhole) {
        // Pixel centres on the image plane at x = 1.
        const double u = ((c + 0.5) / s.columns - 0.5) * 2.0 * std::tan(0.5 * s.horizontal_fov_rad);
        const double v = ((r + 0.5) / s.rows - 0.5) * 2.0 * std::tan(0.5 * s.vertical_fov_rad);
        rays.push_back(Eigen::Vector3d(1.0, -u, -v).normalized());
      } else {
        const double az = 2.0 * kPi * c / s.columns;
        const double el = s.rows == 1
                              ? 0.5 * (s.min_elevation_rad + s.max_elevation_rad)
                              : s.min_elevation_rad +
                                    (s.max_elevation_rad - s.min_elevation_rad) * r / (s.rows - 1);
        rays.emplace_back(std::cos(el) * std::cos(az), std::cos(el) * std::sin(az), std::sin(el));
      }
    }
  return rays;
}

// Cells a viewpoint's rays already counted: a bitmap of the cube its rays can reach (origin
// cell +- half), as the CUDA kernel keeps, emptied between viewpoints by clearing only the
// words that were set; a hash set when that cube would pass kMaxCubeWords (long ranges).
class SeenCube {
 public:
  static constexpr uint64_t kMaxCubeWords = uint64_t(1) << 23;  // 64 MiB

  /// Starts a viewpoint whose rays stay within `half` cells of `centre` (per axis).
  void begin(const VoxelKey& centre, int half) {
    for (uint64_t w : touched_) words_[w] = 0;
    touched_.clear();
    hashed_.clear();
    centre_ = centre;
    half_ = half;
    side_ = 2 * int64_t(half) + 1;
    const uint64_t n = uint64_t((side_ * side_ * side_ + 63) / 64);
    use_hash_ = n > kMaxCubeWords;
    if (!use_hash_ && words_.size() < n) words_.assign(n, 0);
  }
  /// True when `k` was not in the set (it is now).
  bool insert(const VoxelKey& k) {
    const int64_t lx = int64_t(k.x) - centre_.x + half_, ly = int64_t(k.y) - centre_.y + half_,
                  lz = int64_t(k.z) - centre_.z + half_;
    if (lx < 0 || ly < 0 || lz < 0 || lx >= side_ || ly >= side_ || lz >= side_)
      return hashed_
          .insert(~(uint64_t(uint32_t(k.x)) ^ (uint64_t(uint32_t(k.y)) << 21) ^
                    (uint64_t(uint32_t(k.z)) << 42)))
          .second;  // never reached: rays stay within half (kept exact all the same)
    const uint64_t bit = uint64_t((lz * side_ + ly) * side_ + lx);
    if (use_hash_) return hashed_.insert(bit).second;
    uint64_t& word = words_[bit >> 6];
    const uint64_t mask = uint64_t(1) << (bit & 63);
    if (word & mask) return false;
    if (!word) touched_.push_back(bit >> 6);
    word |= mask;
    return true;
  }

 private:
  std::vector<uint64_t> words_;
  std::vector<uint64_t> touched_;
  std::unordered_set<uint64_t> hashed_;
  bool use_hash_ = false;
  VoxelKey centre_;
  int half_ = 0;
  int64_t side_ = 0;
};

// The blocks a viewpoint's rays visit, remembered in a small direct-mapped table: the rays
// of one viewpoint fan out from one cell and cross the same blocks near it again and again,
// where the map's hash lookup is the walk's dearest step.
class NearBlocks {
 public:
  explicit NearBlocks(const BlockView& view) : view_(view) {
    for (Entry& e : entries_) e.key = BlockKey{INT32_MIN, INT32_MIN, INT32_MIN};
  }
  const Block* find(const BlockKey& b) {
    Entry& e = entries_[(uint32_t(b.x) * 3u + uint32_t(b.y) * 5u + uint32_t(b.z) * 7u) & kMask];
    if (e.key != b) {
      e.key = b;
      e.block = view_.findBlock(b);
    }
    return e.block;
  }

 private:
  static constexpr uint32_t kMask = 1023;
  struct Entry {
    BlockKey key;
    const Block* block = nullptr;
  };
  const BlockView& view_;
  Entry entries_[kMask + 1];
};

// Walks one ray (the insertion's DDA, gain_walk.h: the CUDA kernel walks the same
// cells) from `origin_v` along unit `dir` for `length_v` voxels, adding the entropy of each
// unknown cell not seen before; stops after an occupied cell.
double walkRay(const Map& map, NearBlocks& blocks, const double* origin_v, const double* dir,
               double length_v, SeenCube& seen) {
  GainWalk walk = GainWalk::along(origin_v, dir, length_v);
  double gain = 0.0;
  const Block* block = nullptr;
  for (int entry = kUnknownBlock;; entry = walk.next()) {
    const VoxelKey k = walk.cell();
    if (entry != kSameBlock) block = blocks.find(blockKeyOf(k));
    const Cell* cell = block ? &block->cells[cellIndexOf(k)] : nullptr;
    const CellState s = cell ? map.state(*cell) : CellState::kUnknown;
    if (s == CellState::kOccupied) break;
    if (s == CellState::kUnknown && seen.insert(k)) gain += cellGainBits(map.model(), cell);
    if (walk.done()) break;
  }
  return gain;
}

}  // namespace

void GainSensor::validate() const {
  if (columns < 1 || rows < 1)
    throw InvalidArgument(
        fmt::format("gain sensor needs >= 1 column and row, got {} x {}", columns, rows));
  if (!std::isfinite(max_range_m) || max_range_m <= 0.0)
    throw InvalidArgument(
        fmt::format("gain sensor max range must be finite and > 0, got {}", max_range_m));
  if (kind == Kind::kPinhole) {
    for (double fov : {horizontal_fov_rad, vertical_fov_rad})
      if (!std::isfinite(fov) || fov <= 0.0 || fov >= kPi)
        throw InvalidArgument(fmt::format("pinhole field of view must be in (0, pi), got {}", fov));
  } else if (!std::isfinite(min_elevation_rad) || !std::isfinite(max_elevation_rad) ||
             min_elevation_rad > max_elevation_rad || min_elevation_rad < -0.5 * kPi ||
             max_elevation_rad > 0.5 * kPi) {
    throw InvalidArgument(fmt::format("LiDAR elevations must satisfy -pi/2 <= {} <= {} <= pi/2",
                                      min_elevation_rad, max_elevation_rad));
  }
}

void GainDeviceOptions::validate() const {
  if (refill_lanes < 1 || refill_lanes > 32)
    throw InvalidArgument(
        fmt::format("gain kernel refill lanes must be in [1, 32], got {}", refill_lanes));
  if (pool_blocks > (size_t(1) << 31))
    throw InvalidArgument(
        fmt::format("gain kernel pool must hold <= 2^31 blocks, got {}", pool_blocks));
}

const char* gainKernelName(GainKernel kernel) {
  switch (kernel) {
    case GainKernel::kPlain:
      return "plain";
    case GainKernel::kSized:
      return "sized";
    case GainKernel::kPooled:
      return "pooled";
    case GainKernel::kQueued:
      return "queued";
    case GainKernel::kPooledQueued:
      return "pooled-queued";
    case GainKernel::kDeferred:
      return "deferred";
    case GainKernel::kPooledDeferred:
      return "pooled-deferred";
  }
  return "unknown";
}

bool gainKernelPooled(GainKernel kernel) {
  return kernel == GainKernel::kPooled || kernel == GainKernel::kPooledQueued ||
         gainKernelDeferred(kernel);
}

bool gainKernelQueued(GainKernel kernel) {
  return kernel == GainKernel::kQueued || kernel == GainKernel::kPooledQueued ||
         kernel == GainKernel::kDeferred;
}

bool gainKernelDeferred(GainKernel kernel) {
  return kernel == GainKernel::kDeferred || kernel == GainKernel::kPooledDeferred;
}

GainKernel gainKernelFromName(const std::string& name) {
  for (const GainKernel k : kGainKernels)
    if (name == gainKernelName(k)) return k;
  throw InvalidArgument(
      fmt::format("gain kernel must be plain, sized, pooled, queued, pooled-queued, deferred or "
                  "pooled-deferred, got \"{}\"",
                  name));
}

void ViewpointOptions::validate() const {
  sensor.validate();
  device_gains.validate();
  if (radii_m.empty()) throw InvalidArgument("viewpoint rings need at least one radius");
  for (double r : radii_m)
    if (!std::isfinite(r) || r <= 0.0)
      throw InvalidArgument(fmt::format("viewpoint ring radius must be finite and > 0, got {}", r));
  if (heights_m.empty()) throw InvalidArgument("viewpoint rings need at least one height");
  for (double h : heights_m)
    if (!std::isfinite(h)) throw InvalidArgument("viewpoint heights must be finite");
  if (angles < 1)
    throw InvalidArgument(fmt::format("viewpoint angles must be >= 1, got {}", angles));
  if (!std::isfinite(clearance_m) || clearance_m < 0.0)
    throw InvalidArgument(
        fmt::format("viewpoint clearance must be finite and >= 0, got {}", clearance_m));
  if (top_k < 1)
    throw InvalidArgument(fmt::format("viewpoints per cluster (k) must be >= 1, got {}", top_k));
  if (robot_m && !robot_m->allFinite()) throw InvalidArgument("robot position must be finite");
}

double cellEntropyBits(const Map& map, const Cell* cell) { return cellGainBits(map.model(), cell); }

namespace {

// One viewpoint's gain over the sensor's ray directions (sensor frame), already built.
double gainAlongRays(const Map& map, const BlockView& view, const Eigen::Vector3d& position_m,
                     double yaw_rad, const std::vector<Eigen::Vector3d>& rays, double max_range_m) {
  const double res = map.resolution();
  const double origin_v[3] = {position_m.x() / res, position_m.y() / res, position_m.z() / res};
  const double c = std::cos(yaw_rad), s = std::sin(yaw_rad);
  const double length_v = max_range_m / res;
  // Every cell a ray enters lies within ceil(length) + 1 cells of the origin cell per axis.
  thread_local SeenCube seen;
  seen.begin(VoxelKey{int(std::floor(origin_v[0])), int(std::floor(origin_v[1])),
                      int(std::floor(origin_v[2]))},
             static_cast<int>(std::ceil(length_v)) + 2);
  double gain = 0.0;
  NearBlocks blocks(view);
  for (const Eigen::Vector3d& ray : rays) {
    double dir[3];
    yawRotate(c, s, ray.data(), dir);
    gain += walkRay(map, blocks, origin_v, dir, length_v, seen);
  }
  return gain;
}

}  // namespace

double viewpointGainBits(const Map& map, const BlockView& view, const Eigen::Vector3d& position_m,
                         double yaw_rad, const GainSensor& sensor) {
  sensor.validate();
  if (!position_m.allFinite() || !std::isfinite(yaw_rad))
    throw InvalidArgument("viewpoint position and yaw must be finite");
  return gainAlongRays(map, view, position_m, yaw_rad, sensorRays(sensor), sensor.max_range_m);
}

namespace {

// The gains on the map's device layer view (a map on the CUDA backend). False: walk the host
// blocks. Backend::kCuda insists (a CPU map or a device error throws); kAuto falls back with
// one log line when the device cannot take the batch.
bool gainsOnBackend(const Map& map, const std::vector<Eigen::Vector3d>& positions_m,
                    const std::vector<double>& yaws_rad, const std::vector<Eigen::Vector3d>& rays,
                    double max_range_m, Backend backend, const GainDeviceOptions& device,
                    std::vector<double>& gains, GainTimings* timings) {
  const bool on_cuda = std::string(map.backendName()) == "cuda";
  if (!on_cuda) {
    if (backend == Backend::kCuda)
      throw InvalidArgument(
          fmt::format("viewpoint gains on CUDA need a map integrating on CUDA (this one: {})",
                      map.backendName()));
    return false;
  }
  GainBatch batch;
  const double res = map.resolution();
  for (size_t i = 0; i < positions_m.size(); ++i) {
    for (int a = 0; a < 3; ++a) batch.origins_v.push_back(positions_m[i][a] / res);
    batch.cos_yaw.push_back(std::cos(yaws_rad[i]));
    batch.sin_yaw.push_back(std::sin(yaws_rad[i]));
  }
  for (const Eigen::Vector3d& r : rays)
    for (int a = 0; a < 3; ++a) batch.rays_sensor.push_back(r[a]);
  batch.length_v = max_range_m / res;
  try {
#if FRAGG_HAVE_CUDA
    BlockKey lo, hi;
    gainReach(batch, &lo, &hi);
    const auto t0 = std::chrono::steady_clock::now();
    const std::unique_ptr<DeviceViewLease> lease = map.deviceView(lo, hi);
    if (!lease)
      throw CudaOutOfMemory("the device cannot hold every block the viewpoints' rays reach");
    if (timings) {
      *timings = GainTimings{};
      timings->view_seconds = secondsSince(t0);
      DeviceGainStats stats;
      viewpointGainsOnDevice(lease->view(), lease->scratch(), batch, map.model(), device,
                             gains.data(), &stats);
      timings->on_device = true;
      timings->tables_seconds = stats.tables_seconds;
      timings->walk_seconds = stats.walk_seconds;
      timings->rounds = stats.rounds;
      timings->pool_blocks_wanted = stats.pool_blocks_wanted;
      timings->pool_reruns = stats.pool_reruns;
    } else {
      viewpointGainsOnDevice(lease->view(), lease->scratch(), batch, map.model(), device,
                             gains.data());
    }
    return true;
#else
    throw InvalidArgument("viewpoint gains on CUDA: built without CUDA");
#endif
  } catch (const std::exception& e) {
    if (backend == Backend::kCuda) throw;
    logMessage(LogLevel::kWarning, fmt::format("viewpoint gains: on the CPU ({})", e.what()));
    return false;
  }
}

}  // namespace

std::vector<double> viewpointGainsBits(const Map& map,
                                       const std::vector<Eigen::Vector3d>& positions_m,
                                       const std::vector<double>& yaws_rad,
                                       const GainSensor& sensor, int threads, Backend backend,
                                       const GainDeviceOptions& device, GainTimings* timings) {
  sensor.validate();
  device.validate();
  if (positions_m.size() != yaws_rad.size())
    throw InvalidArgument(
        fmt::format("{} viewpoint positions but {} yaws", positions_m.size(), yaws_rad.size()));
  if (threads < 0) throw InvalidArgument(fmt::format("threads must be >= 0, got {}", threads));
  for (size_t i = 0; i < positions_m.size(); ++i)
    if (!positions_m[i].allFinite() || !std::isfinite(yaws_rad[i]))
      throw InvalidArgument(fmt::format("viewpoint {} has a non-finite position or yaw", i));
  const std::vector<Eigen::Vector3d> rays = sensorRays(sensor);
  std::vector<double> gains(positions_m.size());
  if (backend != Backend::kCpu && !positions_m.empty()) {
    if (gainsOnBackend(map, positions_m, yaws_rad, rays, sensor.max_range_m, backend, device, gains,
                       timings))
      return gains;
  }
  const BlockView view = map.blockView();
  const int n_threads = threadCount(threads);
  const int64_t n = static_cast<int64_t>(positions_m.size());
#pragma omp parallel for schedule(dynamic, 1) num_threads(n_threads)
  for (int64_t i = 0; i < n; ++i)
    gains[i] = gainAlongRays(map, view, positions_m[i], yaws_rad[i], rays, sensor.max_range_m);
  return gains;
}

const char* viewpointGainName(ViewpointGain gain) {
  return gain == ViewpointGain::kCoverage ? "coverage" : "entropy";
}

ViewpointGain viewpointGainFromName(const std::string& name) {
  if (name == "entropy") return ViewpointGain::kEntropy;
  if (name == "coverage") return ViewpointGain::kCoverage;
  throw InvalidArgument(
      fmt::format("viewpoint gain must be \"entropy\" or \"coverage\", got \"{}\"", name));
}

namespace {

// Whether the sensor at the origin looking along yaw (cos c, sin s) has `d_m` (map frame,
// relative to the sensor) inside its field of view: the pinhole's image rectangle (as
// sensorRays spans it: |y / x| <= tan(hfov / 2), |z / x| <= tan(vfov / 2), x > 0) or the
// LiDAR's elevation band.
// `tan_half_h`, `tan_half_v`: tan(hfov / 2), tan(vfov / 2) (pinhole).
bool inFieldOfView(const GainSensor& sensor, double tan_half_h, double tan_half_v, double c,
                   double s, const Eigen::Vector3d& d_m) {
  const double x = c * d_m.x() + s * d_m.y(), y = -s * d_m.x() + c * d_m.y(), z = d_m.z();
  if (sensor.kind == GainSensor::Kind::kPinhole) {
    if (x <= 0.0) return false;
    return std::abs(y) <= x * tan_half_h && std::abs(z) <= x * tan_half_v;
  }
  const double elevation = std::atan2(z, std::hypot(x, y));
  return elevation >= sensor.min_elevation_rad && elevation <= sensor.max_elevation_rad;
}

// Whether every cell the segment from `from_v` to the centre of `target` (voxel units) enters
// before `target` is free: the insertion's DDA (gain_walk.h), which ends in the target's cell.
bool lineOfSight(const Map& map, NearBlocks& blocks, const double* from_v, const VoxelKey& target) {
  const double to_v[3] = {target.x + 0.5, target.y + 0.5, target.z + 0.5};
  GainWalk walk(from_v, to_v);
  const Block* block = nullptr;
  while (!walk.done()) {
    const int entry = walk.next();
    const VoxelKey k = walk.cell();
    if (k == target) return true;
    if (entry != kSameBlock || !block) block = blocks.find(blockKeyOf(k));
    if (!block || map.state(block->cells[cellIndexOf(k)]) != CellState::kFree) return false;
  }
  return true;
}

double coverageGain(const Map& map, NearBlocks& blocks, const FrontierCluster& cluster,
                    const Eigen::Vector3d& position_m, double yaw_rad, const GainSensor& sensor) {
  const double res = map.resolution();
  const double from_v[3] = {position_m.x() / res, position_m.y() / res, position_m.z() / res};
  const double c = std::cos(yaw_rad), s = std::sin(yaw_rad);
  const double tan_half_h = std::tan(0.5 * sensor.horizontal_fov_rad);
  const double tan_half_v = std::tan(0.5 * sensor.vertical_fov_rad);
  const double range2 = sensor.max_range_m * sensor.max_range_m;
  double seen = 0.0;
  for (const VoxelKey& k : cluster.cells) {
    const Eigen::Vector3d d_m = map.centerOf(k) - position_m;
    if (d_m.squaredNorm() > range2 || !inFieldOfView(sensor, tan_half_h, tan_half_v, c, s, d_m))
      continue;
    if (lineOfSight(map, blocks, from_v, k)) seen += 1.0;
  }
  return seen;
}

struct Candidate {
  size_t cluster = 0;
  Viewpoint view;
};

// Every cluster's ring candidates whose own cell is free, facing the cluster's centroid.
std::vector<Candidate> ringCandidates(const Map& map, const BlockView& view,
                                      const std::vector<FrontierCluster>& clusters,
                                      const ViewpointOptions& options) {
  std::vector<Candidate> candidates;
  for (size_t ci = 0; ci < clusters.size(); ++ci) {
    const FrontierCluster& cluster = clusters[ci];
    for (double h : options.heights_m)
      for (double r : options.radii_m)
        for (int a = 0; a < options.angles; ++a) {
          const double phi = 2.0 * kPi * a / options.angles;
          Candidate cand;
          cand.cluster = ci;
          Viewpoint& v = cand.view;
          v.position_m =
              cluster.centroid_m + Eigen::Vector3d(r * std::cos(phi), r * std::sin(phi), h);
          const Cell* own = view.findCell(map.keyOf(v.position_m));
          if (!own || map.state(*own) != CellState::kFree) continue;
          const Eigen::Vector3d to_centroid = cluster.centroid_m - v.position_m;
          v.yaw_rad = std::atan2(to_centroid.y(), to_centroid.x());
          candidates.push_back(cand);
        }
  }
  return candidates;
}

// The candidates with `options.clearance_m` of free space around them (one collision batch).
std::vector<Candidate> clearCandidates(const Map& map, std::vector<Candidate> candidates,
                                       const ViewpointOptions& options) {
  if (options.clearance_m <= 0.0 || candidates.empty()) return candidates;
  CollisionOptions clearance;
  clearance.unknown_is_occupied = true;
  const CollisionShape sphere = CollisionShape::sphere(options.clearance_m);
  std::vector<Eigen::Isometry3d> poses;
  poses.reserve(candidates.size());
  for (const Candidate& c : candidates) {
    poses.push_back(Eigen::Isometry3d::Identity());
    poses.back().translation() = c.view.position_m;
  }
  const std::vector<CollisionResult> hits = checkPoses(map, sphere, poses, clearance);
  std::vector<Candidate> clear;
  for (size_t i = 0; i < candidates.size(); ++i)
    if (!hits[i].collides) clear.push_back(candidates[i]);
  return clear;
}

// Gains of every candidate, in pieces of kGainPiece candidates with `control` checked between.
std::vector<double> candidateGains(const Map& map, const BlockView& view,
                                   const std::vector<FrontierCluster>& clusters,
                                   const std::vector<Candidate>& candidates,
                                   const ViewpointOptions& options, int threads,
                                   const QueryControl* control) {
  constexpr size_t kGainPiece = 512;
  std::vector<double> gains(candidates.size());
  const int n_threads = threadCount(threads);
  for (size_t begin = 0; begin < candidates.size(); begin += kGainPiece) {
    checkQuery(control, "frontier viewpoints");
    const size_t end = std::min(candidates.size(), begin + kGainPiece);
    if (options.gain == ViewpointGain::kCoverage) {
      const int64_t n = int64_t(end - begin);
#pragma omp parallel num_threads(n_threads)
      {
        NearBlocks blocks(view);
#pragma omp for schedule(dynamic, 4)
        for (int64_t i = 0; i < n; ++i) {
          const Candidate& c = candidates[begin + size_t(i)];
          gains[begin + size_t(i)] = coverageGain(
              map, blocks, clusters[c.cluster], c.view.position_m, c.view.yaw_rad, options.sensor);
        }
      }
    } else {
      std::vector<Eigen::Vector3d> positions;
      std::vector<double> yaws;
      for (size_t i = begin; i < end; ++i) {
        positions.push_back(candidates[i].view.position_m);
        yaws.push_back(candidates[i].view.yaw_rad);
      }
      const std::vector<double> piece = viewpointGainsBits(
          map, positions, yaws, options.sensor, threads, options.backend, options.device_gains);
      std::copy(piece.begin(), piece.end(), gains.begin() + ptrdiff_t(begin));
    }
  }
  return gains;
}

}  // namespace

double viewpointReachM(const ViewpointOptions& options) {
  double radius = 0.0, height = 0.0;
  for (double r : options.radii_m) radius = std::max(radius, r);
  for (double h : options.heights_m) height = std::max(height, std::abs(h));
  // The centroid lies within the cluster's bounds; a candidate within radius + height of it.
  return radius + height + options.clearance_m +
         (options.gain == ViewpointGain::kEntropy ? options.sensor.max_range_m : 0.0);
}

double coverageGainCells(const Map& map, const BlockView& view, const FrontierCluster& cluster,
                         const Eigen::Vector3d& position_m, double yaw_rad,
                         const GainSensor& sensor) {
  sensor.validate();
  if (!position_m.allFinite() || !std::isfinite(yaw_rad))
    throw InvalidArgument("viewpoint position and yaw must be finite");
  NearBlocks blocks(view);
  return coverageGain(map, blocks, cluster, position_m, yaw_rad, sensor);
}

std::vector<std::vector<Viewpoint>> clustersViewpoints(const Map& map,
                                                       const std::vector<FrontierCluster>& clusters,
                                                       const ViewpointOptions& options, int threads,
                                                       const QueryControl* control) {
  options.validate();
  if (threads < 0) throw InvalidArgument(fmt::format("threads must be >= 0, got {}", threads));
  const BlockView view = map.blockView();
  std::vector<Candidate> candidates = ringCandidates(map, view, clusters, options);
  checkQuery(control, "frontier viewpoints");
  candidates = clearCandidates(map, std::move(candidates), options);
  const std::vector<double> gains =
      candidateGains(map, view, clusters, candidates, options, threads, control);
  std::vector<std::vector<Viewpoint>> out(clusters.size());
  for (size_t i = 0; i < candidates.size(); ++i) {  // in each cluster's candidate order
    Viewpoint v = candidates[i].view;
    v.gain_bits = gains[i];
    if (v.gain_bits <= 0.0) continue;
    v.score = v.gain_bits;
    if (options.robot_m) {
      v.distance_m = (v.position_m - *options.robot_m).norm();
      v.score = v.gain_bits / std::max(v.distance_m, map.resolution());
    }
    out[candidates[i].cluster].push_back(v);
  }
  for (std::vector<Viewpoint>& views : out) {
    std::stable_sort(views.begin(), views.end(),
                     [](const Viewpoint& a, const Viewpoint& b) { return a.score > b.score; });
    if (views.size() > size_t(options.top_k)) views.resize(options.top_k);
  }
  return out;
}

std::vector<Viewpoint> clusterViewpoints(const Map& map, const FrontierCluster& cluster,
                                         const ViewpointOptions& options) {
  return clustersViewpoints(map, std::vector<FrontierCluster>{cluster}, options).front();
}

}  // namespace fragg::planning
