// Collision checks of a shape against a map: one pose, a batch of poses and a path
// (planning/path_check.h), on the CPU (OpenMP threads) or the GPU (CUDA builds), with identical
// answers. A batch classifies the cells of the blocks its poses reach once (obstacle masks);
// on CUDA the kernels read the map's state masks in place through its device layer view (a map
// on the CUDA backend) or an uploaded index (a map on the CPU backend, a prepared map), one
// thread a pose (box, sphere, capsule) or one thread a candidate cell (mesh).
//
// Semantics. A pose collides when some occupied cell's cube overlaps the shape with positive
// volume: the shape must reach more than kTouchEpsilon_m into the cube (the cube shrunk by
// that much on every side must meet the closed shape), so a shape touching a cell's face, edge
// or corner does not collide. For a closed mesh, cells entirely inside the mesh count too; an
// open mesh is a surface (only cells its triangles cut). A cell's state is the map's
// (Map::state, the unknown band included). With unknown_is_occupied, unknown cells count as
// occupied, cells without a block included: the shape's whole cell range is examined.
//
// Margin. margin_m >= 0 grows the shape: box half extents, sphere and capsule radii grow by
// margin_m; a mesh is not offset: instead each cell's cube is grown by margin_m on every side
// (axis-aligned in the map frame) before the triangle test, so a cell collides when it is within
// margin_m of the surface along each map axis (a superset of the true offset surface, by at most
// a factor sqrt(3) along diagonals), or inside a closed mesh.
#pragma once

#include <Eigen/Geometry>
#include <cstdint>
#include <memory>
#include <mutex>
#include <string>
#include <vector>

#include "fragg_map/device_scratch.h"
#include "fragg_map/key.h"
#include "fragg_map/map.h"
#include "fragg_map/map_params.h"
#include "fragg_map/planning/collision_shape.h"

namespace fragg::planning {

/// How far (metres) a shape must reach into a cell's cube to collide with it.
constexpr double kTouchEpsilon_m = 1e-6;

/// Where a CUDA batch of boxes, spheres or capsules prepares its poses (each pose's rotation,
/// grown sizes, capsule ends and cell range): kHost computes them on the batch's threads and
/// uploads them (208 bytes a pose); kDevice uploads the rigid poses as given (96 bytes a pose,
/// in chunks that overlap the host's packing with the copies and kernels) and the kernel
/// computes them with the same function. The answers are identical; CPU checks and meshes
/// ignore it.
enum class PosePreparation { kHost, kDevice };

/// Where a batch's time went (milliseconds on the host's clock), for benchmarks: filled by
/// checkPoses when CollisionOptions::stages points at one.
struct CollisionStages {
  double validate_ms = 0.0;   ///< the poses checked and their box found (one pass)
  double obstacles_ms = 0.0;  ///< the map's device layer view leased, or the obstacle index built
  double poses_ms = 0.0;      ///< CUDA: poses prepared (host) or packed (device, overlapping it)
  double device_ms = 0.0;     ///< CUDA: the rest of the checker's call (an index uploaded, pose
                              ///< copies, kernels, waits, answers back); CPU: the checks
  double results_ms = 0.0;    ///< CUDA: answers turned into results
};

struct CollisionOptions {
  bool unknown_is_occupied = false;
  double margin_m = 0.0;     ///< >= 0; see the header comment for meshes
  bool count_cells = false;  ///< count every colliding cell (otherwise stop at the first)
  int threads = 0;           ///< batches: OpenMP threads (0 = every core)
  PosePreparation pose_preparation = PosePreparation::kHost;  ///< CUDA batches, see above
  /// kDevice: poses a chunk (0: the batch in four chunks of at least 8,192 poses).
  size_t device_chunk_poses = 0;
  /// When set, checkPoses fills it (over a prepared map: its CUDA stages only).
  CollisionStages* stages = nullptr;
};

struct CollisionResult {
  bool collides = false;
  /// Colliding cells (with count_cells; otherwise 1 when the pose collides, else 0).
  uint64_t colliding_cells = 0;
  /// The first colliding cell in scan order (blocks by z, y, x key; cells x fastest within a
  /// block); meaningless when !collides.
  VoxelKey first_cell;
};

/// Throws InvalidArgument for a negative or non-finite margin, a non-finite pose or a rotation
/// that is not orthonormal.
void validate(const CollisionOptions& options);
void validatePose(const Eigen::Isometry3d& T_map_shape);

/// Where a check runs: kCpu (OpenMP), kCuda (throws InvalidArgument without a CUDA build or a
/// device), kAuto (CUDA when built with it and a device is present, else the CPU). `why` gets
/// one line saying what was chosen and why.
Backend resolveCollisionBackend(Backend requested, std::string* why = nullptr);

/// One pose (checks its arguments first).
CollisionResult checkPose(const Map& map, const CollisionShape& shape,
                          const Eigen::Isometry3d& T_map_shape, const CollisionOptions& options,
                          Backend backend = Backend::kCpu);

/// Every pose, in parallel; result i belongs to pose i. Hold the map's read lock.
std::vector<CollisionResult> checkPoses(const Map& map, const CollisionShape& shape,
                                        const std::vector<Eigen::Isometry3d>& T_map_shape,
                                        const CollisionOptions& options,
                                        Backend backend = Backend::kCpu);

/// On a paged map (Map::attachPageStore) const readers see only resident blocks: before a
/// batch, bring back every paged-out block the shape can reach at any of the poses (the poses'
/// box grown by the shape's bounding radius, sqrt(3) margins and one cell). It changes the map
/// (blocks come back into RAM): call it under the write lock, then checkPoses / checkPath under
/// the read lock (a path: pass its waypoints; the segments between them stay within their
/// box). No-op without paging. Throws InvalidArgument for a bad pose or margin (map untouched).
void pageInForCollision(Map& map, const CollisionShape& shape,
                        const std::vector<Eigen::Isometry3d>& T_map_shape,
                        const CollisionOptions& options);

class ObstacleIndex;

/// A map prepared for many collision batches: every block's cells classified once (obstacle
/// masks, for one unknown_is_occupied setting), so that a planner checking batch after batch
/// against an unchanged map pays only for the poses. Checks through it answer exactly as
/// checkPoses on the map. It refers to `map` (which must outlive it); checks throw
/// InvalidArgument once Map::revision() moved on (any insertion or edit), but a map object
/// replaced by assignment (a load into the same variable) is not detected: prepare again.
class PreparedMap {
 public:
  PreparedMap(const Map& map, bool unknown_is_occupied, int threads = 0);
  const Map& map() const { return *map_; }
  bool unknownIsOccupied() const { return unknown_is_occupied_; }
  uint64_t revision() const { return revision_; }
  size_t blockCount() const;  ///< blocks with a stored mask

 private:
  friend std::vector<CollisionResult> checkPoses(const PreparedMap&, const CollisionShape&,
                                                 const std::vector<Eigen::Isometry3d>&,
                                                 const CollisionOptions&, Backend);
  const Map* map_;
  uint64_t revision_;
  bool unknown_is_occupied_;
  std::shared_ptr<const ObstacleIndex> index_;
  /// CUDA checks: the index's device copy and buffers, made on the first such check.
  mutable std::shared_ptr<DeviceScratch> scratch_;
  std::shared_ptr<std::mutex> scratch_mutex_ = std::make_shared<std::mutex>();
};

/// checkPoses over a prepared map (options.unknown_is_occupied must match it).
std::vector<CollisionResult> checkPoses(const PreparedMap& prepared, const CollisionShape& shape,
                                        const std::vector<Eigen::Isometry3d>& T_map_shape,
                                        const CollisionOptions& options,
                                        Backend backend = Backend::kCpu);

}  // namespace fragg::planning
