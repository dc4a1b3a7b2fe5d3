// Map -> OcTree -> octomap_msgs/Octomap, on topics and services.
#include "octomap_outputs.h"

#include <octomap_msgs/GetOctomap.h>
#include <octomap_msgs/Octomap.h>
#include <ros/console.h>
#include <ros/single_subscriber_publisher.h>

#include <memory>
#include <sstream>
#include <string>

#include "flush_without_waiting.h"
#include "fragg_map/interop/octomap_io.h"
#include "map_copy.h"

namespace fragg::ros {
namespace {

// As octomap_msgs' binaryMapToMsg / fullMapToMsg fill it, from the map under its read lock.
// The full tree is pruned with `prune_full` (compress_map), as octomap_server's tree is.
octomap_msgs::Octomap octomapMsg(const fragg::Map& map, bool binary, bool prune_full,
                                 const std::string& frame_id, const ::ros::Time& stamp) {
  std::string bytes;
  if (binary) {
    const std::unique_ptr<octomap::OcTree> tree = fragg::toOcTree(map);
    std::stringstream data;
    tree->toMaxLikelihood();
    tree->prune();
    tree->writeBinaryData(data);
    bytes = data.str();
  } else {
    bytes = fragg::octomapFullData(map, prune_full);
  }
  octomap_msgs::Octomap msg;
  msg.header.frame_id = frame_id;
  msg.header.stamp = stamp;
  msg.binary = binary;
  msg.id = "OcTree";  // toOcTree's tree type
  msg.resolution = map.resolution();
  msg.data.assign(bytes.begin(), bytes.end());
  return msg;
}

}  // namespace

OctomapOutputs::OctomapOutputs(::ros::NodeHandle& nh, const ServerParams& params, SharedMap* shared)
    : params_(params), shared_(shared), held_(params.map_rate_hz) {
  auto to_new_subscriber = [this](bool binary) -> ::ros::SubscriberStatusCallback {
    return [this, binary](const ::ros::SingleSubscriberPublisher& sub) {
      std::lock_guard<std::mutex> publishing(publish_mutex_);
      try {
        sub.publish(octomapMsg(shared_->read("octomap late subscriber")->map, binary,
                               params_.octomap.compress_map, params_.frame_id, ::ros::Time::now()));
      } catch (const std::exception& e) {
        ROS_ERROR_THROTTLE(5.0, "fragg_map: publishing failed: %s", e.what());
      }
    };
  };
  binary_pub_ = nh.advertise<octomap_msgs::Octomap>("octomap_binary", 1, to_new_subscriber(true),
                                                    ::ros::SubscriberStatusCallback(),
                                                    ::ros::VoidConstPtr(), params_.latch);
  full_pub_ = nh.advertise<octomap_msgs::Octomap>("octomap_full", 1, to_new_subscriber(false),
                                                  ::ros::SubscriberStatusCallback(),
                                                  ::ros::VoidConstPtr(), params_.latch);
  auto service = [this](bool binary) {
    return [this, binary](octomap_msgs::GetOctomap::Request&,
                          octomap_msgs::GetOctomap::Response& res) {
      try {
        // The tree is built from a copy of the observed cells, taken under the read lock:
        // insertion waits for the copy only (the service has a thread of its own).
        const fragg::Map copy = observedCopy(shared_->read("octomap late subscriber")->map);
        res.map = octomapMsg(copy, binary, params_.octomap.compress_map, params_.frame_id,
                             ::ros::Time::now());
        return true;
      } catch (const std::exception& e) {
        ROS_WARN("fragg_map: %s refused: %s", binary ? "octomap_binary" : "octomap_full", e.what());
        return false;
      }
    };
  };
  binary_srv_ =
      nh.advertiseService<octomap_msgs::GetOctomap::Request, octomap_msgs::GetOctomap::Response>(
          "octomap_binary", service(true));
  full_srv_ =
      nh.advertiseService<octomap_msgs::GetOctomap::Request, octomap_msgs::GetOctomap::Response>(
          "octomap_full", service(false));
  if (held_.throttle().limited())
    flush_timer_ = nh.createSteadyTimer(::ros::WallDuration(held_.throttle().flushTickS()),
                                        &OctomapOutputs::flushPending, this);
}

void OctomapOutputs::publish(const ::ros::Time& stamp) { publishIfDue(stamp, false); }

void OctomapOutputs::publishAfterInsert(const ::ros::Time& stamp) { publishIfDue(stamp, true); }

void OctomapOutputs::publishIfDue(const ::ros::Time& stamp, bool throttled) {
  // Nobody to send to: a later subscriber gets the current map when it connects.
  if (binary_pub_.getNumSubscribers() == 0 && full_pub_.getNumSubscribers() == 0) return;
  std::lock_guard<std::mutex> publishing(publish_mutex_);
  const double now_s = ::ros::SteadyTime::now().toSec();
  if (throttled && !held_.letThrough(now_s, stamp)) return;
  const SharedMap::ReadGuard state = shared_->read("octomap topics");
  publishLocked(state->map, stamp, now_s);
}

void OctomapOutputs::publishLocked(const fragg::Map& map, const ::ros::Time& stamp, double now_s) {
  const bool binary = binary_pub_.getNumSubscribers() > 0;
  const bool full = full_pub_.getNumSubscribers() > 0;
  if (!binary && !full) {
    held_.drop();
    return;
  }
  held_.published(now_s);  // also when building throws: the next cloud tries again
  if (binary)
    binary_pub_.publish(
        octomapMsg(map, true, params_.octomap.compress_map, params_.frame_id, stamp));
  if (full)
    full_pub_.publish(
        octomapMsg(map, false, params_.octomap.compress_map, params_.frame_id, stamp));
}

void OctomapOutputs::flushPending(const ::ros::SteadyTimerEvent&) {
  const double now_s = ::ros::SteadyTime::now().toSec();
  flushWithoutWaiting(
      publish_mutex_, *shared_, [this, now_s] { return held_.flushDue(now_s); },
      [this, now_s](const fragg::Map& map) { publishLocked(map, held_.pendingStamp(), now_s); });
}

}  // namespace fragg::ros
