// Conversion, tf wait and insertion of one cloud; every fault counted and logged once per
// throttle period by cause.
#include "cloud_inserter.h"

#include <ros/console.h>
#include <tf2/exceptions.h>
#include <tf2_eigen/tf2_eigen.h>

#include <algorithm>
#include <chrono>
#include <cmath>
#include <limits>
#include <optional>
#include <thread>

#include "fragg_map/errors.h"
#include "fragg_map/internal/rigid_pose.h"
#include "fragg_map/lock_holders.h"
#include "fragg_map/ros/cloud_from_msg.h"

namespace fragg::ros {
namespace {

// Half the int32 voxel key range: a sensor within it and a point within it of the sensor keep
// the ray's end inside the range (the ray preparation refuses ends beyond ~2^31).
constexpr double kHalfKeyRangeVox = 1073741824.0;  // 2^30
// The tolerance Map::insert checks sensor poses with (map.cpp, validatePose).
constexpr double kRigidTolerance = 1e-4;

bool hasUsablePoint(const fragg::PointCloud& cloud) {
  for (const Eigen::Vector3f& p : cloud.points_S)
    if (p.allFinite() && !p.isZero()) return true;
  return false;
}

}  // namespace

bool stampBeforeBuffer(const std::string& tf_error) {
  // tf2 says "extrapolation into the past" when every transform of the chain it holds is
  // later than the stamp, and "extrapolation at time X, but only time Y is in the buffer"
  // when a frame holds one transform: with X < Y the stamp is older too (a cloud that waited
  // in the queue while its transforms aged out). Waiting brings only later transforms.
  if (tf_error.find("into the past") != std::string::npos) return true;
  static const std::string kAt = "extrapolation at time ";
  static const std::string kOnly = "but only time ";
  const size_t at = tf_error.find(kAt), only = tf_error.find(kOnly);
  if (at == std::string::npos || only == std::string::npos) return false;
  try {
    const double requested_s = std::stod(tf_error.substr(at + kAt.size()));
    const double held_s = std::stod(tf_error.substr(only + kOnly.size()));
    return requested_s < held_s;
  } catch (const std::exception&) {  // not the message we know: not too old
    return false;
  }
}

TfWait waitForTransform(const tf2::BufferCore& tf, const std::string& target,
                        const std::string& source, const ::ros::Time& stamp, double tolerance_s,
                        const std::atomic<bool>& stop, Eigen::Isometry3d* T_target_source,
                        std::string* error) {
  const auto deadline =
      std::chrono::steady_clock::now() + std::chrono::duration<double>(tolerance_s);
  while (!stop) {
    error->clear();  // canTransform appends its reason
    if (tf.canTransform(target, source, stamp, error)) {
      try {
        *T_target_source = tf2::transformToEigen(tf.lookupTransform(target, source, stamp));
        return TfWait::kFound;
      } catch (const tf2::TransformException& e) {  // the buffer changed in between
        *error = e.what();
      }
    }
    if (stampBeforeBuffer(*error)) return TfWait::kTooOld;
    if (std::chrono::steady_clock::now() >= deadline) return TfWait::kTimedOut;
    std::this_thread::sleep_for(std::chrono::milliseconds(5));
  }
  return TfWait::kStopped;
}

size_t dropBeyondKeyRange(fragg::PointCloud* cloud, double resolution_m) {
  const double limit_m = kHalfKeyRangeVox * resolution_m;
  const double limit2 = limit_m * limit_m;
  auto beyond = [limit2](const Eigen::Vector3f& p) {
    return p.allFinite() && p.cast<double>().squaredNorm() > limit2;
  };
  size_t n = 0;
  if (cloud->organised()) {
    const float nan = std::numeric_limits<float>::quiet_NaN();
    for (Eigen::Vector3f& p : cloud->points_S)
      if (beyond(p)) {
        p.setConstant(nan);
        ++n;
      }
    return n;
  }
  auto& pts = cloud->points_S;
  const auto end = std::remove_if(pts.begin(), pts.end(), beyond);
  n = static_cast<size_t>(pts.end() - end);
  pts.erase(end, pts.end());
  return n;
}

std::optional<std::string> transformProblem(const Eigen::Isometry3d& T_map_sensor,
                                            double resolution_m) {
  try {
    fragg::requireRigidPose(T_map_sensor, "the transform to the map frame", kRigidTolerance);
  } catch (const fragg::InvalidArgument& e) {
    return std::string(e.what());
  }
  const double reach_m = kHalfKeyRangeVox * resolution_m;
  if (T_map_sensor.translation().cwiseAbs().maxCoeff() > reach_m)
    return "the sensor is " + std::to_string(T_map_sensor.translation().norm()) +
           " m from the map origin, beyond the map's key range (" + std::to_string(reach_m) + " m)";
  return std::nullopt;
}

CloudInserter::CloudInserter(const ServerParams& params, SharedMap* shared, ServerStats* stats)
    : params_(params), shared_(shared), stats_(stats) {}

std::optional<fragg::PointCloud> CloudInserter::convert(const sensor_msgs::PointCloud2& msg,
                                                        std::vector<Eigen::Vector3f> reuse) const {
  fragg::PointCloud cloud;
  cloud.points_S = std::move(reuse);
  try {
    if (msg.header.frame_id.empty()) throw fragg::InvalidArgument("cloud has no frame_id");
    if (msg.width == 0 || msg.height == 0) {
      // Drivers publish empty clouds (a LiDAR between scans, a camera that saw nothing): not a
      // fault, so counted quietly (~stats empty_clouds) and logged at DEBUG only.
      stats_->addEmptyCloud();
      ROS_DEBUG_THROTTLE(5.0, "fragg_map: empty cloud from '%s' skipped (width %u, height %u)",
                         msg.header.frame_id.c_str(), msg.width, msg.height);
      return std::nullopt;
    }
    cloudFromMsg(msg, &cloud);
  } catch (const std::exception& e) {
    // cloudFromMsg's last check: no finite point (all NaN) is a cause of its own.
    const bool no_point = std::string(e.what()).find("no finite point") != std::string::npos;
    stats_->addFault(no_point ? CloudFault::kNoFinitePoint : CloudFault::kMalformed);
    if (no_point)
      ROS_WARN_THROTTLE(5.0, "fragg_map: cloud from '%s' dropped: %s (%lu such so far)",
                        msg.header.frame_id.c_str(), e.what(),
                        static_cast<unsigned long>(stats_->faults(CloudFault::kNoFinitePoint)));
    else
      ROS_ERROR_THROTTLE(5.0, "fragg_map: rejected cloud from '%s': %s (%lu malformed so far)",
                         msg.header.frame_id.c_str(), e.what(),
                         static_cast<unsigned long>(stats_->faults(CloudFault::kMalformed)));
    return std::nullopt;
  }
  const size_t far = dropBeyondKeyRange(&cloud, params_.map.resolution_m);
  stats_->addPointsInvalid(far);
  if (!hasUsablePoint(cloud)) {
    stats_->addFault(CloudFault::kNoFinitePoint);
    ROS_WARN_THROTTLE(5.0,
                      "fragg_map: cloud from '%s' dropped: no usable point (%lu beyond the map's "
                      "key range, the others NaN, Inf or 0; %lu such clouds so far)",
                      msg.header.frame_id.c_str(), static_cast<unsigned long>(far),
                      static_cast<unsigned long>(stats_->faults(CloudFault::kNoFinitePoint)));
    return std::nullopt;
  }
  if (far > 0)
    ROS_WARN_THROTTLE(5.0,
                      "fragg_map: cloud from '%s': %lu points beyond the map's key range left "
                      "out (counted in ~stats points_invalid)",
                      msg.header.frame_id.c_str(), static_cast<unsigned long>(far));
  return cloud;
}

bool CloudInserter::insert(const fragg::PointCloud& cloud, const Eigen::Isometry3d& T_map_sensor,
                           int64_t stamp_ns, const std::string& frame, fragg::InsertStats* inserted,
                           std::vector<Eigen::Vector3f>* dynamic_points_S, double* lock_wait_ms,
                           std::string* lock_holders) const {
  if (const auto problem = transformProblem(T_map_sensor, params_.map.resolution_m)) {
    stats_->addFault(CloudFault::kBadTransform);
    ROS_ERROR_THROTTLE(5.0, "fragg_map: cloud from '%s' dropped: %s (%lu such so far)",
                       frame.c_str(), problem->c_str(),
                       static_cast<unsigned long>(stats_->faults(CloudFault::kBadTransform)));
    return false;
  }
  const auto start = std::chrono::steady_clock::now();
  // The first clouds' beam spacing, outside the lock (a few ms, first clouds only).
  std::optional<planning::BeamSpacing> beams;
  if (beam_estimates_.load(std::memory_order_relaxed) < planning::BeamSpacingTracker::kClouds) {
    ++beam_estimates_;
    beams = planning::estimateBeamSpacing(cloud.points_S);
  }
  bool fell_back = false;
  try {
    // One scan per lock: a query waits for this scan at most. The map drops points outside
    // the height band (pointcloud_min_z/max_z) and resolves an `auto` sensor, as for the CLI.
    const auto asked = std::chrono::steady_clock::now();
    std::vector<fragg::LockHolder> waited_for;
    const SharedMap::WriteGuard state = shared_->write("insertion", &waited_for);
    const double waited_ms =
        std::chrono::duration<double, std::milli>(std::chrono::steady_clock::now() - asked).count();
    if (lock_wait_ms) *lock_wait_ms = waited_ms;
    if (!waited_for.empty()) {
      const std::string holders = fragg::describeLockHolders(waited_for);
      if (waited_ms >= kLongLockWaitMs)
        ROS_WARN_THROTTLE(10.0, "fragg_map: a cloud waited %.0f ms for the map's write lock: %s",
                          waited_ms, holders.c_str());
      if (lock_holders) *lock_holders = holders;
    } else if (lock_holders) {
      lock_holders->clear();
    }
    const std::string backend_before = state->map.backendName();
    *inserted = state->map.insert(cloud, T_map_sensor, params_.sensor, stamp_ns, frame);
    if (dynamic_points_S) *dynamic_points_S = state->map.lastDynamicPoints_S();
    if (state->map.scanStore().contains(inserted->scan_id))
      state->stamps.add(stamp_ns, inserted->scan_id, frame);
    fell_back = state->map.backendName() != backend_before;
    if (beams) state->beams.add(*beams);
  } catch (const std::exception& e) {
    stats_->addFault(CloudFault::kInsertFailed);
    ROS_ERROR_THROTTLE(5.0, "fragg_map: cloud from '%s' not inserted: %s (%lu such so far)",
                       frame.c_str(), e.what(),
                       static_cast<unsigned long>(stats_->faults(CloudFault::kInsertFailed)));
    return false;
  }
  if (fell_back) {
    stats_->addBackendFallback();
    ROS_ERROR(
        "fragg_map: the CUDA backend ran out of device memory; the map goes on with the "
        "CPU backend (counted in ~stats backend_fallbacks)");
  }
  const double ms =
      std::chrono::duration<double, std::milli>(std::chrono::steady_clock::now() - start).count();
  stats_->addInsertion(cloud.size(), ms, *inserted);
  return true;
}

}  // namespace fragg::ros
