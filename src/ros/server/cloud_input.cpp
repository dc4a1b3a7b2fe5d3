// cloud_in subscriber, drop-oldest queue and the insertion thread.
#include "cloud_input.h"

#include <ros/console.h>

#include <string>
#include <vector>

#include "fragg_map/ros/ground_filter.h"
#include "fragg_map/ros/occupied_cloud.h"

namespace fragg::ros {
namespace {

std::string withoutLeadingSlash(const std::string& frame) {
  return !frame.empty() && frame[0] == '/' ? frame.substr(1) : frame;
}

GroundFilterParams groundFilterParamsOf(const OctomapCompatParams& o) {
  GroundFilterParams g;
  g.distance_m = o.ground_distance_m;
  g.angle_rad = o.ground_angle_rad;
  g.plane_distance_m = o.ground_plane_distance_m;
  return g;
}

}  // namespace

CloudInput::CloudInput(::ros::NodeHandle& nh, const ServerParams& params, const tf2_ros::Buffer& tf,
                       SharedMap* shared, ServerStats* stats, InsertedFn on_inserted)
    : params_(params),
      tf_(tf),
      stats_(stats),
      inserter_(params, shared, stats),
      on_inserted_(std::move(on_inserted)),
      queue_(static_cast<size_t>(params.queue_size)) {
  // MapParams::dynamic: the points of each scan classified dynamic (sensor frame), built only
  // while someone listens.
  if (params_.map.dynamic.enabled)
    dynamic_pub_ = nh.advertise<sensor_msgs::PointCloud2>("dynamic_points", 1);
  worker_ = std::thread([this] { run(); });
  // The subscription on a callback queue of its own with one thread: onCloud only moves the
  // message into queue_, so it runs at once even while every thread of the node's queue waits
  // for the map lock in a service call. Otherwise roscpp's subscription queue would drop the
  // clouds arriving meanwhile, silently, and only the drops counted here are in ~stats.
  ::ros::SubscribeOptions options = ::ros::SubscribeOptions::create<sensor_msgs::PointCloud2>(
      "cloud_in", static_cast<uint32_t>(params_.queue_size),
      [this](const sensor_msgs::PointCloud2::ConstPtr& msg) { onCloud(msg); }, ::ros::VoidPtr(),
      &callbacks_);
  sub_ = nh.subscribe(options);
  spinner_ = std::make_unique<::ros::AsyncSpinner>(1, &callbacks_);
  spinner_->start();
}

CloudInput::~CloudInput() {
  sub_.shutdown();
  if (spinner_) spinner_->stop();
  stopping_ = true;
  queue_.close();
  if (worker_.joinable()) worker_.join();
}

void CloudInput::onCloud(const sensor_msgs::PointCloud2::ConstPtr& msg) {
  if (queue_.push(msg)) {
    stats_->addDroppedQueueFull();
    ROS_WARN_THROTTLE(5.0,
                      "fragg_map: clouds arrive faster than they are inserted; dropped the "
                      "oldest waiting cloud (%lu dropped so far, queue_size %d)",
                      static_cast<unsigned long>(queue_.dropped()), params_.queue_size);
  }
}

void CloudInput::run() {
  sensor_msgs::PointCloud2::ConstPtr msg;
  while (queue_.pop(&msg)) {
    try {
      process(*msg);
    } catch (const std::exception& e) {  // the inserter counts its faults; this is a last guard
      stats_->addFault(CloudFault::kInsertFailed);
      ROS_ERROR_THROTTLE(5.0, "fragg_map: cloud from '%s' not inserted: %s",
                         msg->header.frame_id.c_str(), e.what());
    }
  }
}

bool CloudInput::waitForTransform(const std::string& target_frame,
                                  const sensor_msgs::PointCloud2& msg,
                                  Eigen::Isometry3d* T_target_sensor) {
  const std::string source = withoutLeadingSlash(msg.header.frame_id);
  std::string error;
  const TfWait got =
      fragg::ros::waitForTransform(tf_, target_frame, source, msg.header.stamp,
                                   params_.tf_tolerance_s, stopping_, T_target_sensor, &error);
  if (got == TfWait::kFound) return true;
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
  return false;
}

void CloudInput::process(const sensor_msgs::PointCloud2& msg) {
  std::optional<fragg::PointCloud> cloud = inserter_.convert(msg);  // before the tf wait
  if (!cloud) return;
  Eigen::Isometry3d T_map_sensor;
  if (!waitForTransform(params_.frame_id, msg, &T_map_sensor)) return;
  if (params_.octomap.filter_ground) {
    Eigen::Isometry3d T_base_sensor;
    if (!waitForTransform(params_.octomap.base_frame_id, msg, &T_base_sensor)) return;
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
  fragg::InsertStats inserted;
  const bool publish_dynamic = dynamic_pub_ && dynamic_pub_.getNumSubscribers() > 0;
  std::vector<Eigen::Vector3f> dynamic_S;
  if (!inserter_.insert(*cloud, T_map_sensor, static_cast<int64_t>(msg.header.stamp.toNSec()),
                        withoutLeadingSlash(msg.header.frame_id), &inserted,
                        publish_dynamic ? &dynamic_S : nullptr))
    return;
  if (publish_dynamic) {
    std::vector<float> xyz;
    xyz.reserve(3 * dynamic_S.size());
    for (const Eigen::Vector3f& p : dynamic_S) xyz.insert(xyz.end(), {p.x(), p.y(), p.z()});
    dynamic_pub_.publish(packedXyzCloud(xyz, msg.header.frame_id, msg.header.stamp));
  }
  if (on_inserted_) on_inserted_(msg, inserted.sensor, T_map_sensor);
}

}  // namespace fragg::ros
