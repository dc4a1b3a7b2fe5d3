// The map server's insertion path without the subscriber: a bounded drop-oldest queue and the
// insertion thread that converts each cloud, waits for its transform to frame_id at the cloud's
// stamp (up to tf_tolerance of wall time, none for a stamp older than the tf buffer) and
// inserts it (CloudInserter: the map's write lock for that one scan only, taken after the
// transform is known). No ROS master needed: CloudInput feeds it from cloud_in, the tests call
// offer() directly.
//
// Every cloud offered lands in exactly one counter of ServerStats (clouds_received =
// clouds_inserted + dropped_clouds + empty_clouds + clouds_in_flight): a queue drop, a tf
// failure (no_tf or tf_too_old, also after a wait in the queue), a rejection, an insertion
// failure or an insertion. A failure of the publishing hook after an insertion is logged, not
// counted as a cloud fault (the cloud is in the map).
#pragma once

#include <sensor_msgs/PointCloud2.h>
#include <tf2/buffer_core.h>

#include <Eigen/Geometry>
#include <atomic>
#include <chrono>
#include <functional>
#include <memory>
#include <string>
#include <thread>
#include <vector>

#include "cloud_inserter.h"
#include "cloud_trace.h"
#include "fragg_map/ros/drop_oldest_queue.h"
#include "fragg_map/ros/server_params.h"
#include "server_stats.h"
#include "shared_map.h"

namespace fragg::ros {

class CloudPipeline {
 public:
  /// Called on the insertion thread after each insertion (the map is not locked), with the
  /// sensor model the map used (an `auto` model resolved for the cloud), the message
  /// (colored_map reads its colours) and where the cloud's trace takes the outputs' parts.
  using InsertedFn =
      std::function<void(const sensor_msgs::PointCloud2& msg, const fragg::SensorModel&,
                         const Eigen::Isometry3d& T_map_sensor, PublishTimes* times)>;

  /// Called on the insertion thread after a cloud's work (its trace row written, its latency
  /// counted) when no other cloud waits: upkeep that would otherwise fall on a cloud's path
  /// (MapPublishers::betweenClouds). A cloud that arrives meanwhile waits in the queue (its
  /// queue_ms shows it); the time goes into the finished cloud's trace as between_ms.
  using BetweenFn = std::function<void()>;

  /// The points of a scan classified dynamic (MapParams::dynamic; sensor frame), for the
  /// `dynamic_points` topic: `wanted` says whether anyone listens (asked before the insertion),
  /// `publish` gets them after it with the cloud's message.
  struct DynamicOutput {
    std::function<bool()> wanted;
    std::function<void(const sensor_msgs::PointCloud2& msg,
                       const std::vector<Eigen::Vector3f>& points_S)>
        publish;
  };

  /// Starts the insertion thread. `tf` outlives the pipeline. With params.trace_csv, opens
  /// that file (throws fragg::IoError when it cannot) for one row per cloud.
  CloudPipeline(const ServerParams& params, const tf2::BufferCore& tf, SharedMap* shared,
                ServerStats* stats, InsertedFn on_inserted, DynamicOutput dynamic = {},
                BetweenFn between_clouds = {});
  ~CloudPipeline();  ///< stops the insertion thread; clouds still waiting are discarded
  CloudPipeline(const CloudPipeline&) = delete;
  CloudPipeline& operator=(const CloudPipeline&) = delete;

  /// A cloud received (counted in clouds_received): queued for the insertion thread; when the
  /// queue is full its oldest cloud is dropped (counted in dropped_queue_full).
  void offer(const sensor_msgs::PointCloud2::ConstPtr& msg);
  /// Clouds waiting in the queue now (not counting the one being inserted).
  [[nodiscard]] size_t waiting() const { return queue_.size(); }

 private:
  using Clock = std::chrono::steady_clock;
  struct Queued {
    sensor_msgs::PointCloud2::ConstPtr msg;
    Clock::time_point received;
  };
  void run();
  /// Converts, transforms, inserts and publishes one cloud; fills `trace` (times, outcome).
  void process(const Queued& item, CloudTrace* trace);
  /// T_target_sensor at the cloud's stamp, waiting up to tf_tolerance (not at all for a stamp
  /// older than the buffer); unless kFound the cloud is counted as dropped by cause and a
  /// warning logged.
  TfWait waitForTransform(const std::string& target_frame, const sensor_msgs::PointCloud2& msg,
                          Eigen::Isometry3d* T_target_sensor);
  static double msBetween(Clock::time_point a, Clock::time_point b) {
    return std::chrono::duration<double, std::milli>(b - a).count();
  }

  const ServerParams params_;
  const tf2::BufferCore& tf_;
  ServerStats* stats_;
  CloudInserter inserter_;
  /// The last cloud's point buffer, converted into by the next (the insertion thread's only).
  std::vector<Eigen::Vector3f> spare_points_;
  InsertedFn on_inserted_;
  DynamicOutput dynamic_;
  BetweenFn between_clouds_;
  DropOldestQueue<Queued> queue_;
  std::unique_ptr<CloudTraceCsv> trace_csv_;  ///< null without trace_csv
  std::atomic<bool> stopping_{false};
  std::thread worker_;  // last: its thread uses everything above
};

}  // namespace fragg::ros
