// `frontiers` and `frontier_cells`: incremental frontier cells, clusters and viewpoints at
// frontiers/rate_hz while someone listens.
#include "frontier_publisher.h"

#include <ros/console.h>

#include <chrono>
#include <optional>
#include <vector>

#include "fragg_map/planning/viewpoints.h"
#include "fragg_map/ros/frontier_markers.h"

namespace fragg::ros {

FrontierPublisher::FrontierPublisher(::ros::NodeHandle& nh, const ServerParams& params,
                                     SharedMap* shared, ServerStats* stats)
    : params_(params),
      shared_(shared),
      stats_(stats),
      tracker_(params.frontiers.filter, params.map.threads),
      clusterer_(params.frontiers.clusters) {
  markers_pub_ = nh.advertise<visualization_msgs::MarkerArray>("frontiers", 1, params_.latch);
  cloud_pub_ = nh.advertise<sensor_msgs::PointCloud2>("frontier_cells", 1, params_.latch);
  timer_ = nh.createSteadyTimer(::ros::WallDuration(1.0 / params_.frontiers.rate_hz),
                                &FrontierPublisher::onTimer, this);
  ROS_INFO(
      "fragg_map: frontiers and frontier_cells at most %.2f Hz while subscribed, at most %d "
      "cells each (frontiers/max_marker_cells), %d viewpoints per cluster",
      params_.frontiers.rate_hz, params_.frontiers.max_marker_cells, params_.frontiers.viewpoints);
}

void FrontierPublisher::onTimer(const ::ros::SteadyTimerEvent&) {
  const uint32_t marker_subs = markers_pub_.getNumSubscribers();
  const uint32_t cloud_subs = cloud_pub_.getNumSubscribers();
  std::lock_guard<std::mutex> lock(mutex_);
  // Only the markers' clusters and viewpoints read the mirror: without a marker subscriber
  // its memory (a copy of the observed cells) goes.
  if (marker_subs == 0) mirror_.clear();
  if (marker_subs == 0 && cloud_subs == 0) {  // nobody listens: no work
    marker_subscribers_ = cloud_subscribers_ = 0;
    return;
  }
  const bool joined = marker_subs > marker_subscribers_ || cloud_subs > cloud_subscribers_;
  marker_subscribers_ = marker_subs;
  cloud_subscribers_ = cloud_subs;

  const FrontierParams& fp = params_.frontiers;
  const auto t0 = std::chrono::steady_clock::now();
  std::vector<VoxelKey> cells;
  std::vector<planning::FrontierCluster> clusters;
  std::vector<std::vector<planning::Viewpoint>> views;
  double resolution_m = 0.0;
  uint64_t revision = 0;
  planning::FrontierUpdateStats update;
  // The tracker's input (the changed-block list with masks, or every block's masks for a full
  // update) is copied under the map's read lock and the tracker updated without it, so that a
  // long update (the first one on a big map) never holds insertion back. The obstacle distance
  // filter reads cells: with it the update runs under the lock.
  const bool copy_first = fp.filter.min_obstacle_distance_m <= 0.0;
  try {
    std::optional<planning::FrontierMapChanges> changes;
    {
      const SharedMap::ReadGuard state = shared_->read("frontier topics");
      revision = state->map.revision();
      if (published_ && revision == published_revision_ && !joined) return;
      resolution_m = state->map.resolution();
      if (copy_first)
        changes.emplace(tracker_.collect(state->map));
      else
        update = tracker_.update(state->map);
    }
    if (changes) update = tracker_.apply(*changes);
    cells = tracker_.cells();
    if (marker_subs > 0) {
      // Clusters and viewpoints read the cells around the frontier: on the mirror of the
      // observed cells (they answer as on the map), brought up to date a piece per read lock
      // (a whole-map copy under one lock held insertion back for seconds on a big map).
      mirror_.refresh(*shared_);
      const Map& states = mirror_.map();
      clusters = clusterer_.cluster(states, cells);
      if (fp.viewpoints > 0) {
        views.resize(clusters.size());
        for (size_t i = 0; i < clusters.size(); ++i)
          views[i] = planning::clusterViewpoints(states, clusters[i], fp.views);
      }
    }
  } catch (const std::exception& e) {
    ROS_ERROR_THROTTLE(5.0, "fragg_map: frontier update failed: %s", e.what());
    return;
  }
  const double ms =
      std::chrono::duration<double, std::milli>(std::chrono::steady_clock::now() - t0).count();
  // Counted before the messages go out, so that whoever receives them sees the count.
  stats_->addFrontierUpdate(update.full, update.blocks_examined, cells.size(), ms);
  const ::ros::Time stamp = ::ros::Time::now();
  const uint64_t cap = static_cast<uint64_t>(fp.max_marker_cells);
  if (cells.size() > cap && !warned_cap_) {
    ROS_INFO(
        "fragg_map: %zu frontier cells: frontiers and frontier_cells carry an even subsample "
        "of at most %llu (frontiers/max_marker_cells)",
        cells.size(), static_cast<unsigned long long>(cap));
    warned_cap_ = true;
  }
  if (marker_subs > 0) {
    FrontierMarkerInput in;
    in.clusters = &clusters;
    in.views = &views;
    in.resolution_m = resolution_m;
    markers_pub_.publish(frontierMarkers(in, params_.frame_id, stamp, cap));
  }
  if (cloud_subs > 0)
    cloud_pub_.publish(frontierCloud(cells, resolution_m, params_.frame_id, stamp, cap));
  published_ = true;
  published_revision_ = revision;
  ROS_DEBUG(
      "fragg_map: frontiers at revision %llu: %zu cells, %zu clusters, %llu blocks examined "
      "(%s), %.1f ms",
      static_cast<unsigned long long>(revision), cells.size(), clusters.size(),
      static_cast<unsigned long long>(update.blocks_examined), update.full ? "full" : "incremental",
      ms);
}

}  // namespace fragg::ros
