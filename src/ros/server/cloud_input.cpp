// cloud_in subscriber on a callback queue and thread of its own, feeding the CloudPipeline.
#include "cloud_input.h"

#include <vector>

#include "fragg_map/ros/occupied_cloud.h"

namespace fragg::ros {

CloudInput::CloudInput(::ros::NodeHandle& nh, const ServerParams& params, const tf2_ros::Buffer& tf,
                       SharedMap* shared, ServerStats* stats, InsertedFn on_inserted,
                       BetweenFn between_clouds)
    : pipeline_(
          params, tf, shared, stats, std::move(on_inserted),
          CloudPipeline::DynamicOutput{
              [this] { return dynamic_pub_ && dynamic_pub_.getNumSubscribers() > 0; },
              [this](const sensor_msgs::PointCloud2& msg,
                     const std::vector<Eigen::Vector3f>& points_S) {
                std::vector<float> xyz;
                xyz.reserve(3 * points_S.size());
                for (const Eigen::Vector3f& p : points_S)
                  xyz.insert(xyz.end(), {p.x(), p.y(), p.z()});
                dynamic_pub_.publish(packedXyzCloud(xyz, msg.header.frame_id, msg.header.stamp));
              }},
          std::move(between_clouds)) {
  // MapParams::dynamic: the points of each scan classified dynamic (sensor frame), built only
  // while someone listens (advertised before the subscription below brings the first cloud).
  if (params.map.dynamic.enabled)
    dynamic_pub_ = nh.advertise<sensor_msgs::PointCloud2>("dynamic_points", 1);
  // The subscription on a callback queue of its own with one thread: the callback only moves
  // the message into the pipeline's queue, so it runs at once even while every thread of the
  // node's queue waits for the map lock in a service call. Otherwise roscpp's subscription
  // queue would drop the clouds arriving meanwhile, silently, and only the drops counted by
  // the pipeline are in ~stats.
  ::ros::SubscribeOptions options = ::ros::SubscribeOptions::create<sensor_msgs::PointCloud2>(
      "cloud_in", static_cast<uint32_t>(params.queue_size),
      [this](const sensor_msgs::PointCloud2::ConstPtr& msg) { pipeline_.offer(msg); },
      ::ros::VoidPtr(), &callbacks_);
  sub_ = nh.subscribe(options);
  spinner_ = std::make_unique<::ros::AsyncSpinner>(1, &callbacks_);
  spinner_->start();
}

CloudInput::~CloudInput() {
  sub_.shutdown();
  if (spinner_) spinner_->stop();
  // pipeline_ (declared first) stops its thread last.
}

}  // namespace fragg::ros
