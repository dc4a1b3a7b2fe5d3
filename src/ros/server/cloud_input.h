// Input of the map server: cloud_in -> bounded drop-oldest queue -> insertion thread. The
// thread converts each cloud, waits for its transform to frame_id at the cloud's stamp (up to
// tf_tolerance of wall time, none for a stamp older than the tf buffer; then the cloud is
// dropped and counted) and inserts it (the map filters it by height in the map frame), taking
// the map's write lock for that one scan, so the subscriber thread never does more than
// enqueue. The subscription has a callback queue and a thread of its own: a service waiting for
// the map lock on the node's threads cannot hold clouds back in roscpp's subscription queue,
// which would drop them uncounted; every drop is the drop-oldest queue's, in ~stats. The steps and
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

#include <atomic>
#include <functional>
#include <memory>
#include <thread>

#include "cloud_inserter.h"
#include "fragg_map/ros/drop_oldest_queue.h"
#include "fragg_map/ros/server_params.h"
#include "server_stats.h"
#include "shared_map.h"

namespace fragg::ros {

class CloudInput {
 public:
  /// Called on the insertion thread after each insertion (the map is not locked), with the
  /// sensor model the map used (an `auto` model resolved for the cloud) and the message
  /// (colored_map reads its colours).
  using InsertedFn =
      std::function<void(const sensor_msgs::PointCloud2& msg, const fragg::SensorModel&,
                         const Eigen::Isometry3d& T_map_sensor)>;

  CloudInput(::ros::NodeHandle& nh, const ServerParams& params, const tf2_ros::Buffer& tf,
             SharedMap* shared, ServerStats* stats, InsertedFn on_inserted);
  ~CloudInput();  ///< stops the insertion thread
  CloudInput(const CloudInput&) = delete;
  CloudInput& operator=(const CloudInput&) = delete;

 private:
  void onCloud(const sensor_msgs::PointCloud2::ConstPtr& msg);
  void run();
  void process(const sensor_msgs::PointCloud2& msg);
  /// T_target_sensor at the cloud's stamp, waiting up to tf_tolerance (not at all for a stamp
  /// older than the buffer); false (the cloud counted as dropped by cause and a warning
  /// logged) when it does not come.
  bool waitForTransform(const std::string& target_frame, const sensor_msgs::PointCloud2& msg,
                        Eigen::Isometry3d* T_target_sensor);

  const ServerParams params_;
  const tf2_ros::Buffer& tf_;
  ServerStats* stats_;
  CloudInserter inserter_;
  InsertedFn on_inserted_;
  DropOldestQueue<sensor_msgs::PointCloud2::ConstPtr> queue_;
  std::atomic<bool> stopping_{false};
  ::ros::CallbackQueue callbacks_;  ///< cloud_in's only (onCloud), before sub_ and spinner_
  ::ros::Subscriber sub_;
  ::ros::Publisher dynamic_pub_;  ///< dynamic_points (MapParams::dynamic enabled only)
  std::unique_ptr<::ros::AsyncSpinner> spinner_;  ///< one thread on callbacks_
  std::thread worker_;
};

}  // namespace fragg::ros
