// Input of the map server: cloud_in -> CloudPipeline (bounded drop-oldest queue -> insertion
// thread: conversion, the transform, then the insertion under the map's write lock for that
// one scan; cloud_pipeline.h), so the subscriber thread never does more than enqueue. The
// subscription has a callback queue and a thread of its own: a service waiting for the map
// lock on the node's threads cannot hold clouds back in roscpp's subscription queue, which
// would drop them uncounted; every drop is the drop-oldest queue's, in ~stats. The steps and
// their faults: cloud_inserter.h. With filter_ground the cloud's ground points (sought in
// base_frame_id, which then needs a transform too) are marked free-only before insertion
// (fragg_map/ros/ground_filter.h).
//
// Why not tf2_ros::MessageFilter: Debian's MessageFilter has no per-message timeout (a cloud
// whose tf never comes waits until its queue overflows), and it would run the callback on the
// subscriber's queue; waiting in the insertion thread gives both the bound and the threading.
#pragma once

#include <ros/callback_queue.h>
#include <ros/node_handle.h>
#include <ros/publisher.h>
#include <ros/spinner.h>
#include <ros/subscriber.h>
#include <sensor_msgs/PointCloud2.h>
#include <tf2_ros/buffer.h>

#include <memory>

#include "cloud_pipeline.h"
#include "fragg_map/ros/server_params.h"
#include "server_stats.h"
#include "shared_map.h"

namespace fragg::ros {

class CloudInput {
 public:
  using InsertedFn = CloudPipeline::InsertedFn;
  using BetweenFn = CloudPipeline::BetweenFn;

  /// Subscribes to cloud_in; `on_inserted` publishes after each insertion, `between_clouds`
  /// (may be empty) runs when a cloud's work is done and no other waits.
  CloudInput(::ros::NodeHandle& nh, const ServerParams& params, const tf2_ros::Buffer& tf,
             SharedMap* shared, ServerStats* stats, InsertedFn on_inserted,
             BetweenFn between_clouds = {});
  ~CloudInput();  ///< stops the subscription, then the insertion thread
  CloudInput(const CloudInput&) = delete;
  CloudInput& operator=(const CloudInput&) = delete;

 private:
  /// dynamic_points (MapParams::dynamic enabled only): before pipeline_, whose insertion thread
  /// publishes on it, so that it outlives that thread.
  ::ros::Publisher dynamic_pub_;
  CloudPipeline pipeline_;
  ::ros::CallbackQueue callbacks_;  ///< cloud_in's only, before sub_ and spinner_
  ::ros::Subscriber sub_;
  std::unique_ptr<::ros::AsyncSpinner> spinner_;  ///< one thread on callbacks_
};

}  // namespace fragg::ros
