// The drop-oldest queue and the insertion thread: convert, transform, insert, publish.
#include "cloud_pipeline.h"

#include <ros/console.h>

#include <optional>
#include <string>

#include "fragg_map/ros/ground_filter.h"
#include "frame_text.h"

namespace fragg::ros {
namespace {

GroundFilterParams groundFilterParamsOf(const OctomapCompatParams& o) {
  GroundFilterParams g;
  g.distance_m = o.ground_distance_m;
  g.angle_rad = o.ground_angle_rad;
  g.plane_distance_m = o.ground_plane_distance_m;
  return g;
}

}  // namespace

CloudPipeline::CloudPipeline(const ServerParams& params, const tf2::BufferCore& tf,
                             SharedMap* shared, ServerStats* stats, InsertedFn on_inserted,
                             DynamicOutput dynamic, BetweenFn between_clouds)
    : params_(params),
      tf_(tf),
      stats_(stats),
      inserter_(params, shared, stats),
      on_inserted_(std::move(on_inserted)),
      dynamic_(std::move(dynamic)),
      between_clouds_(std::move(between_clouds)),
      queue_(static_cast<size_t>(params.queue_size)) {
  if (!params.trace_csv.empty()) trace_csv_ = std::make_unique<CloudTraceCsv>(params.trace_csv);
  worker_ = std::thread([this] { run(); });
}

CloudPipeline::~CloudPipeline() {
  stopping_ = true;
  queue_.close();
  if (worker_.joinable()) worker_.join();
}

void CloudPipeline::offer(const sensor_msgs::PointCloud2::ConstPtr& msg) {
  stats_->addReceived();
  Queued dropped;
  if (queue_.push(Queued{msg, Clock::now()}, &dropped)) {
    stats_->addDroppedQueueFull();
    ROS_WARN_THROTTLE(5.0,
                      "fragg_map: clouds arrive faster than they are inserted; dropped the "
                      "oldest waiting cloud (%lu dropped so far, queue_size %d)",
                      static_cast<unsigned long>(queue_.dropped()), params_.queue_size);
    if (trace_csv_) {
      CloudTrace trace;
      trace.stamp_s = dropped.msg->header.stamp.toSec();
      trace.points = uint64_t{dropped.msg->width} * dropped.msg->height;
      trace.outcome = "queue_full";
      trace.queue_ms = trace.total_ms = msBetween(dropped.received, Clock::now());
      trace_csv_->write(trace);
    }
  }
}

void CloudPipeline::run() {
  Queued item;
  while (queue_.pop(&item)) {
    CloudTrace trace;
    trace.stamp_s = item.msg->header.stamp.toSec();
    trace.points = uint64_t{item.msg->width} * item.msg->height;
    trace.queue_depth = queue_.size();
    try {
      process(item, &trace);
    } catch (const std::exception& e) {  // the inserter counts its faults; this is a last guard
      stats_->addFault(CloudFault::kInsertFailed);
      trace.outcome = "insert_failed";
      ROS_ERROR_THROTTLE(5.0, "fragg_map: cloud from '%s' not inserted: %s",
                         item.msg->header.frame_id.c_str(), e.what());
    }
    trace.total_ms = msBetween(item.received, Clock::now());
    if (trace.outcome == "inserted")
      stats_->addLatency(trace.queue_ms, trace.tf_ms, trace.publish_ms, trace.total_ms);
    if (between_clouds_ && trace.outcome == "inserted" && queue_.size() == 0 && !stopping_) {
      const Clock::time_point started = Clock::now();
      try {
        between_clouds_();
      } catch (const std::exception& e) {  // the cloud is in the map: logged, not counted
        ROS_ERROR_THROTTLE(5.0, "fragg_map: work between clouds failed: %s", e.what());
      }
      trace.between_ms = msBetween(started, Clock::now());
    }
    if (trace_csv_ && !trace.outcome.empty()) trace_csv_->write(trace);
  }
}

TfWait CloudPipeline::waitForTransform(const std::string& target_frame,
                                       const sensor_msgs::PointCloud2& msg,
                                       Eigen::Isometry3d* T_target_sensor) {
  const std::string source = withoutLeadingSlash(msg.header.frame_id);
  std::string error;
  const TfWait got =
      fragg::ros::waitForTransform(tf_, target_frame, source, msg.header.stamp,
                                   params_.tf_tolerance_s, stopping_, T_target_sensor, &error);
  if (got == TfWait::kFound) return got;
  if (got == TfWait::kTooOld) {
    stats_->addFault(CloudFault::kTfTooOld);
    ROS_WARN_THROTTLE(5.0,
                      "fragg_map: cloud from '%s' at %.3f is older than the tf buffer holds; "
                      "dropped (%lu so far): %s",
                      source.c_str(), msg.header.stamp.toSec(),
                      static_cast<unsigned long>(stats_->faults(CloudFault::kTfTooOld)),
                      error.c_str());
  } else if (got == TfWait::kTimedOut) {
    stats_->addDroppedNoTf();
    ROS_WARN_THROTTLE(5.0,
                      "fragg_map: no transform %s <- %s at %.3f within tf_tolerance %.2f s; "
                      "cloud dropped (%lu so far): %s",
                      target_frame.c_str(), source.c_str(), msg.header.stamp.toSec(),
                      params_.tf_tolerance_s, static_cast<unsigned long>(stats_->droppedNoTf()),
                      error.c_str());
  }
  // kStopped: the server shuts down; the cloud stays in clouds_in_flight.
  return got;
}

void CloudPipeline::process(const Queued& item, CloudTrace* trace) {
  const sensor_msgs::PointCloud2& msg = *item.msg;
  const Clock::time_point taken = Clock::now();
  trace->queue_ms = msBetween(item.received, taken);
  trace->outcome = "rejected";  // until a later step says otherwise
  // Into the last cloud's point buffer (before the tf wait); the buffer is kept again for the
  // next cloud however this one ends.
  std::optional<fragg::PointCloud> cloud = inserter_.convert(msg, std::move(spare_points_));
  struct KeepPoints {
    std::optional<fragg::PointCloud>& cloud;
    std::vector<Eigen::Vector3f>& spare;
    ~KeepPoints() {
      if (cloud) spare = std::move(cloud->points_S);
    }
  } keep{cloud, spare_points_};
  if (!cloud) {
    trace->outcome = msg.width == 0 || msg.height == 0 ? "empty" : "rejected";
    return;
  }
  // Every transform is looked up before the map's write lock is taken (inserter_.insert).
  auto tfFailed = [&](TfWait got) {
    trace->tf_ms = msBetween(taken, Clock::now());
    trace->outcome = got == TfWait::kTooOld    ? "tf_too_old"
                     : got == TfWait::kStopped ? std::string()
                                               : "no_tf";
  };
  Eigen::Isometry3d T_map_sensor;
  TfWait got = waitForTransform(params_.frame_id, msg, &T_map_sensor);
  if (got != TfWait::kFound) return tfFailed(got);
  if (params_.octomap.filter_ground) {
    Eigen::Isometry3d T_base_sensor;
    got = waitForTransform(params_.octomap.base_frame_id, msg, &T_base_sensor);
    if (got != TfWait::kFound) return tfFailed(got);
    const GroundSplit split =
        markGroundPoints(T_base_sensor, groundFilterParamsOf(params_.octomap), &*cloud);
    ROS_DEBUG("fragg_map: %zu of %zu points are ground (%s)", split.ground, split.points,
              split.plane_found ? "plane" : "no plane: height band around z = 0");
    if (!split.plane_found && split.points >= 50)
      ROS_WARN_THROTTLE(5.0,
                        "fragg_map: no ground plane found in a cloud; points within %.3f m "
                        "of z = 0 in %s taken as ground",
                        params_.octomap.ground_plane_distance_m,
                        params_.octomap.base_frame_id.c_str());
  }
  const Clock::time_point transformed = Clock::now();
  trace->tf_ms = msBetween(taken, transformed);
  fragg::InsertStats inserted;
  const bool publish_dynamic = dynamic_.wanted && dynamic_.publish && dynamic_.wanted();
  std::vector<Eigen::Vector3f> dynamic_S;
  const bool ok = inserter_.insert(
      *cloud, T_map_sensor, static_cast<int64_t>(msg.header.stamp.toNSec()),
      withoutLeadingSlash(msg.header.frame_id), &inserted, publish_dynamic ? &dynamic_S : nullptr,
      &trace->lock_wait_ms, &trace->lock_holders);
  const Clock::time_point done = Clock::now();
  trace->insert_ms = msBetween(transformed, done);
  if (!ok) {
    trace->outcome = "insert_failed";  // or an unusable transform: both counted by the inserter
    return;
  }
  trace->outcome = "inserted";
  // The cloud is counted (inserted): a failure to publish is not a fault of the cloud.
  if (publish_dynamic) {
    try {
      dynamic_.publish(msg, dynamic_S);
    } catch (const std::exception& e) {
      ROS_ERROR_THROTTLE(5.0, "fragg_map: dynamic_points not published: %s", e.what());
    }
  }
  if (!on_inserted_) return;
  try {
    on_inserted_(msg, inserted.sensor, T_map_sensor, &trace->publish);
  } catch (const std::exception& e) {
    ROS_ERROR_THROTTLE(5.0, "fragg_map: publishing after an insertion failed: %s", e.what());
  }
  trace->publish_ms = msBetween(done, Clock::now());
}

}  // namespace fragg::ros
