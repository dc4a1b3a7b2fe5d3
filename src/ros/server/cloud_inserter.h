// The map server's way from a received PointCloud2 to the map, without the subscriber and the
// queue (cloud_input.h) so that every fault is testable without a ROS master: conversion and
// validation (cloudFromMsg; points beyond the map's key range removed), the wait for the
// transform (tf2::BufferCore), and the insertion under the map's write lock. Each fault is
// counted in ServerStats (CloudFault), logged in one throttled line per cause, and leaves the
// map unchanged; nothing throws.
#pragma once

#include <sensor_msgs/PointCloud2.h>
#include <tf2/buffer_core.h>

#include <Eigen/Geometry>
#include <atomic>
#include <optional>
#include <string>
#include <vector>

#include "fragg_map/insert_stats.h"
#include "fragg_map/point_cloud.h"
#include "fragg_map/ros/server_params.h"
#include "server_stats.h"
#include "shared_map.h"

namespace fragg::ros {

/// The outcome of waiting for a cloud's transform.
enum class TfWait {
  kFound,     ///< the transform is in T_map_sensor
  kTimedOut,  ///< none within the tolerance (missing frame, stamp later than the tf received)
  kTooOld,    ///< the stamp is older than the buffer holds: it will never come
  kStopped,   ///< `stop` was raised while waiting
};

/// Whether tf2's error `tf_error` (canTransform's) says the stamp is older than every
/// transform the buffer holds for the chain, so that waiting cannot help.
[[nodiscard]] bool stampBeforeBuffer(const std::string& tf_error);

/// Polls `tf` for target <- source at `stamp` for up to `tolerance_s` seconds of wall time
/// (every 5 ms), returning at once when the stamp is older than the buffer's data for that
/// pair. `error` gets tf's reason when the result is not kFound.
TfWait waitForTransform(const tf2::BufferCore& tf, const std::string& target,
                        const std::string& source, const ::ros::Time& stamp, double tolerance_s,
                        const std::atomic<bool>& stop, Eigen::Isometry3d* T_target_source,
                        std::string* error);

/// Points whose distance from the sensor, in voxels of `resolution_m`, exceeds half the map's
/// key range are removed from an unorganised cloud and made NaN in an organised one (they
/// would be refused by the ray preparation anyway, but an unlimited max_range would first be
/// stretched to them). Returns how many.
size_t dropBeyondKeyRange(fragg::PointCloud* cloud, double resolution_m);

/// Null when `T_map_sensor` is usable: finite and rigid (as Map::insert checks it: rotation
/// orthonormal within 1e-4, determinant +1), sensor within half the map's key range of the
/// origin; else the reason.
std::optional<std::string> transformProblem(const Eigen::Isometry3d& T_map_sensor,
                                            double resolution_m);

class CloudInserter {
 public:
  CloudInserter(const ServerParams& params, SharedMap* shared, ServerStats* stats);

  /// The cloud of `msg`, validated; nullopt (counted, logged) when it is malformed or holds no
  /// usable point, and nullopt (counted as empty_clouds, logged at DEBUG only) when it has 0
  /// points. `reuse`: a point buffer to convert into (its capacity kept: the last cloud's, so
  /// that clouds of one size take no fresh memory).
  std::optional<fragg::PointCloud> convert(const sensor_msgs::PointCloud2& msg,
                                           std::vector<Eigen::Vector3f> reuse = {}) const;

  /// Inserts `cloud` (sensor frame `frame`) at `T_map_sensor` under the write lock. False
  /// (counted, logged, map unchanged) for an unusable transform or when the map throws.
  /// Counts the scan's left-out points and a CUDA -> CPU fallback. `dynamic_points_S` (when
  /// given) gets the scan's points classified dynamic (MapParams::dynamic), sensor frame.
  /// `lock_wait_ms` (when given) gets the time spent waiting for the write lock, and
  /// `lock_holders` whom it waited for (fragg::describeLockHolders; empty: the lock was free).
  /// A wait over kLongLockWaitMs is logged with its holders (throttled).
  bool insert(const fragg::PointCloud& cloud, const Eigen::Isometry3d& T_map_sensor,
              int64_t stamp_ns, const std::string& frame, fragg::InsertStats* inserted,
              std::vector<Eigen::Vector3f>* dynamic_points_S = nullptr,
              double* lock_wait_ms = nullptr, std::string* lock_holders = nullptr) const;
  /// A wait for the write lock this long (ms) is logged with whom it waited for.
  static constexpr double kLongLockWaitMs = 100.0;

 private:
  const ServerParams params_;
  SharedMap* shared_;
  ServerStats* stats_;
  /// Clouds whose beam spacing was estimated (MapState::beams), at most BeamSpacingTracker's
  /// kClouds: later clouds cost nothing.
  mutable std::atomic<size_t> beam_estimates_{0};
};

}  // namespace fragg::ros
