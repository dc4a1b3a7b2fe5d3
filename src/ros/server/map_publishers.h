// Every topic the map server publishes. Messages are built only for topics with subscribers
// (or, but for the markers, for every topic when latched). occupied_cells_vis_array and
// free_cells_vis_array are incremental (one marker per chunk of blocks that changed, from the
// state masks and the change log; block_markers.h); they are republished in full after a reset
// or load, and a new subscriber gets the whole map as its first message. occupied_cells,
// octomap_point_cloud_centers and projected_map always carry the whole map, assembled from
// per-block pieces that only the changed blocks refresh (MapOutputCache). With `marker_rate` the
// marker updates are throttled: the insertion thread publishes them when one is due, and a steady
// timer sends what is still pending once the clouds stop. `map_rate` throttles the whole-map
// outputs the same way. With `paced_outputs` (the default) the work behind both is spread over
// the clouds: after every cloud the marker topics send their share of the changed chunks (every
// chunk within 1 / marker_rate of its change) and the output cache recomputes its share of the
// changed blocks and then, once they are in, gathers the next occupied cloud message (the
// whole-map messages, when due, carry the cache as it is: each block within two periods of its
// change; both go to roscpp already serialised, wire_payload.h); unpaced, after a cloud that is not
// due nothing is done (the ledgers and the cache catch up from the revision they last saw at the
// next update). Reset, load, clear and corrections publish the whole-map outputs at once; frustum
// and ~stats go out after every cloud. On a CUDA map the incremental outputs read a mask mirror
// (the changed blocks' state masks copied from the device, after every cloud while the outputs
// are paced and read) instead of writing the device's changed blocks back to the host first.
#pragma once

#include <ros/node_handle.h>
#include <ros/publisher.h>
#include <ros/steady_timer.h>
#include <sensor_msgs/PointCloud2.h>

#include <Eigen/Geometry>
#include <memory>
#include <mutex>
#include <optional>
#include <string>

#include "cloud_trace.h"
#include "fragg_map/ros/block_markers.h"
#include "fragg_map/ros/cell_colors.h"
#include "fragg_map/ros/output_cache.h"
#include "fragg_map/ros/rate_throttle.h"
#include "fragg_map/ros/server_params.h"
#include "server_stats.h"
#include "shared_map.h"

namespace fragg::ros {

class MapPublishers {
 public:
  MapPublishers(::ros::NodeHandle& nh, ::ros::NodeHandle& private_nh, const ServerParams& params,
                SharedMap* shared, const ServerStats* stats);

  /// After an insertion of `cloud` (stamp, and with colored_map its colours): incremental
  /// markers (throttled by marker_rate), occupied cloud and projected map (throttled by
  /// map_rate), frustum, stats. Takes the map's read lock itself. `times` (when given) gets
  /// where the time went (the cloud's trace).
  void publishAfterInsert(const sensor_msgs::PointCloud2& cloud, const fragg::SensorModel& sensor,
                          const Eigen::Isometry3d& T_map_sensor, PublishTimes* times = nullptr);
  /// Between clouds (the insertion thread, when no cloud waits): with mirror_every_cloud on a
  /// CUDA map whose paced outputs someone reads, the mask mirror takes in the changes of the
  /// clouds since its last sync, so that the next cloud's take-ins read it as it stands (one
  /// insertion behind: MaskMirror::acceptLag) instead of syncing a period's changes on that
  /// cloud's path; with shares_between_clouds (either backend) the output cache then takes its
  /// share and the markers' next share is built (sharesBetweenClouds, markerSharesBetweenClouds).
  /// Takes the publishers' mutex and the map's read lock; nothing when none of these is on.
  void betweenClouds();
  /// After a pose correction, a truncation or a merge: the markers of the blocks it changed
  /// (incremental, as after an insertion; throttled by marker_rate), occupied cloud, projected
  /// map (at once: not throttled), stats. Takes the read lock.
  void publishAfterCorrection(const ::ros::Time& stamp);
  /// After reset, load or clear: a full marker republish and the other map topics.
  void publishFull(const ::ros::Time& stamp);

 private:
  struct MarkerTopic {
    ::ros::Publisher pub;
    MarkerStyle style;
    MarkerLedger ledger;
    uint32_t subscribers = 0;  ///< at the last update
    /// The next cloud's share, built between clouds (shares_between_clouds): that cloud's path
    /// publishes it instead of building one (on a CUDA map the mirror state its take-ins would
    /// read; on a CPU map the map one insertion older).
    std::optional<SerializedMarkerArray> prepared;
  };
  // Callers hold publish_mutex_ and the map's read lock.
  /// Markers (a full set, or the changes when due), whole-map outputs (with `throttle_maps`
  /// only when map_rate lets them out) and stats; `times` (when given) gets each part's ms.
  void publishMaps(const fragg::Map& map, const ::ros::Time& stamp, bool full_markers,
                   bool throttle_maps, PublishTimes* times = nullptr);
  /// occupied_cells, octomap_point_cloud_centers and projected_map: the cache brought up to
  /// date and the messages sent; when `throttled` and not due, nothing but a note that they
  /// are pending.
  void publishMapOutputs(const fragg::Map& map, const ::ros::Time& stamp, bool throttled);
  /// Both marker topics: a full set, or the changes when the throttle lets an update out.
  void publishMarkerTopics(const fragg::Map& map, const ::ros::Time& stamp, bool full);
  /// One topic: a full set, or the changes (paced with `period_s` > 0: this cloud's share).
  void publishMarkers(const fragg::Map& map, MarkerTopic& topic, const ::ros::Time& stamp,
                      bool full, double now_s, double period_s);
  /// occupied_cells, octomap_point_cloud_centers and projected_map from the cache as it is.
  void sendMapOutputs(const ::ros::Time& stamp, bool cloud_wanted, bool grid_wanted);
  /// On a map whose blocks live on a device (CUDA), the first call (the start-up publication)
  /// makes and syncs the mask mirror that the output cache and both marker ledgers read from
  /// then on (MaskMirror: their take-ins copy the changed blocks' masks, not the blocks);
  /// nothing on a CPU map.
  void mirrorFor(const fragg::Map& map);
  /// Paced outputs on a CUDA map take a period's changes in at once: the mask mirror's sync of
  /// a second's changed blocks (~90 k at W1 5 cm: 11-17 ms on an H100) was the node's p99
  /// latency. betweenClouds: the mirror takes each cloud's changes in after that cloud (while
  /// anyone reads the mirror's outputs). Whether it is on: mirror_every_cloud, a mirror, paced
  /// outputs and someone to read them. Nothing on a CPU map (no mirror).
  [[nodiscard]] bool followsChanges() const;
  /// Whether the output cache's paced shares run between clouds (betweenClouds) rather than on
  /// each cloud's path: shares_between_clouds, paced whole-map outputs and someone to send
  /// them to (either backend: on a CUDA map after the mirror's sync). A publication's call
  /// (the listing, the grid, the messages) stays on the path of the cloud it is due after, and
  /// a cloud after which no gap ran a share takes its share on its path.
  [[nodiscard]] bool sharesBetweenClouds() const;
  /// The same for the markers: shares_between_clouds, paced markers and a subscriber. The share
  /// is built between clouds and published on the next cloud's path (a publication stays on a
  /// cloud's path); with none built, that path builds one.
  [[nodiscard]] bool markerSharesBetweenClouds() const;
  /// Between clouds: `topic`'s next share built into topic.prepared (when it has subscribers,
  /// a started ledger, no new subscriber and no share waiting).
  void prepareMarkers(const fragg::Map& map, MarkerTopic& topic, double now_s);
  /// paced_outputs with a marker_rate / map_rate limit in effect.
  bool pacedMarkers() const { return params_.paced_outputs && marker_throttle_.limited(); }
  bool pacedMaps() const { return params_.paced_outputs && held_maps_.throttle().limited(); }
  /// Timer: the changes still pending (never waits for the map: an insertion holding it
  /// publishes them itself when it ends).
  void flushPendingMarkers(const ::ros::SteadyTimerEvent& event);
  /// Timer: the whole-map outputs held back by map_rate, once due (never waits for the map).
  void flushPendingMaps(const ::ros::SteadyTimerEvent& event);
  void sendAllMarkersTo(MarkerTopic& topic, const ::ros::SingleSubscriberPublisher& sub);
  bool wanted(const ::ros::Publisher& pub) const;
  /// colored_map in effect: as octomap_server, height_map wins when both are set.
  bool coloredMap() const { return params_.octomap.colored_map && !params_.octomap.height_map; }
  /// Unlatched topics: the current message to a subscriber that connects late (a latched
  /// topic's publisher keeps the last one itself).
  ::ros::SubscriberStatusCallback currentMessageTo(const ::ros::Publisher* pub);

  const ServerParams params_;
  SharedMap* shared_;
  const ServerStats* stats_;
  /// The publishers' own state (marker ledgers, throttle): readers of the map run at once
  /// (insertion thread, services, timer), so they take this first, then the map's read lock.
  std::mutex publish_mutex_;
  /// colored_map: the cells' colours (under publish_mutex_), drawn by the occupied markers.
  CellColors colors_;
  MarkerTopic occupied_markers_;
  MarkerTopic free_markers_;
  /// The last inserted cloud's stamp (under publish_mutex_): the stamp of marker shares built
  /// between clouds (they show the map as of that cloud).
  ::ros::Time last_cloud_stamp_;
  /// The output cache took a share between clouds since the last cloud's outputs (the next
  /// cloud's path takes none).
  bool cache_share_between_ = false;
  RateThrottle marker_throttle_;
  ::ros::SteadyTimer marker_flush_timer_;
  /// The occupied cloud's and projected map's pieces (under publish_mutex_).
  MapOutputCache outputs_;
  /// mirrorFor's mirror (under publish_mutex_), null on a CPU map.
  std::shared_ptr<MaskMirror> mirror_;
  /// map_rate: whether the whole-map outputs are held back, with the last cloud's stamp.
  HeldBackUpdate<::ros::Time> held_maps_;
  ::ros::SteadyTimer map_flush_timer_;
  ::ros::Publisher occupied_cloud_pub_;
  ::ros::Publisher centers_pub_;  ///< octomap_point_cloud_centers: octomap_server's name
  ::ros::Publisher projected_map_pub_;
  ::ros::Publisher frustum_pub_;
  ::ros::Publisher stats_pub_;
};

}  // namespace fragg::ros
