// The `frontiers` (visualization_msgs/MarkerArray: cells coloured by cluster, viewpoint
// arrows coloured by gain) and `frontier_cells` (sensor_msgs/PointCloud2 of cell centres)
// topics. A steady timer at frontiers/rate_hz brings a planning::FrontierTracker up to date
// (only the blocks changed since its last update and their neighbours are examined again) and
// publishes, but only while one of the topics has a subscriber and only when the map changed
// or a subscriber joined: with nobody listening the timer does no work at all. Cluster ids stay
// the same while a cluster's cells do (one FrontierClusterer for the topic's lifetime). The
// tracker's input (the changed-block list with masks: FrontierTracker::collect) is copied under
// the map's read lock and the tracker updated without it (but with the obstacle distance filter,
// which reads cells); the clusters and viewpoints (markers only) on a mirror of the observed
// cells (observed_mirror.h: the blocks changed since the last tick copied a piece per read
// lock, so a big map never holds insertion back for the copy; dropped while the markers have
// no subscriber);
// at most frontiers/max_marker_cells cells go out (an even subsample beyond it, logged). The
// timer runs on a thread of its own (service_threads.h).
#pragma once

#include <ros/node_handle.h>
#include <ros/publisher.h>
#include <ros/steady_timer.h>

#include <cstdint>
#include <mutex>

#include "fragg_map/planning/frontier_clusters.h"
#include "fragg_map/planning/frontier_tracker.h"
#include "fragg_map/ros/server_params.h"
#include "observed_mirror.h"
#include "server_stats.h"
#include "shared_map.h"

namespace fragg::ros {

class FrontierPublisher {
 public:
  FrontierPublisher(::ros::NodeHandle& nh, const ServerParams& params, SharedMap* shared,
                    ServerStats* stats);

 private:
  void onTimer(const ::ros::SteadyTimerEvent& event);

  const ServerParams params_;
  SharedMap* shared_;
  ServerStats* stats_;
  std::mutex mutex_;  ///< the tracker, the clusterer and the bookkeeping below
  planning::FrontierTracker tracker_;
  planning::FrontierClusterer clusterer_;
  ObservedMirror mirror_;  ///< the observed cells the clusters and viewpoints read
  bool published_ = false;
  uint64_t published_revision_ = 0;
  /// Subscribers of each topic at the last timer tick (one more gets a fresh update).
  uint32_t marker_subscribers_ = 0, cloud_subscribers_ = 0;
  bool warned_cap_ = false;
  ::ros::Publisher markers_pub_;
  ::ros::Publisher cloud_pub_;
  ::ros::SteadyTimer timer_;
};

}  // namespace fragg::ros
