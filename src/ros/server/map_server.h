// The map server: parameters, the shared map, tf, and its parts (input, publishers, services,
// loop-closure correction through ~correct_poses and corrected_path, sub-maps through ~truncate
// and ~merge, collision checks through ~check_collision, frontiers through ~get_frontiers and
// the frontiers / frontier_cells topics, the autosave (autosave.h). MapServerNodelet::onInit
// builds one; it holds no logic of its own. The services, the frontier topics' timer and the
// octomap outputs run on threads of their own, one per group (service_threads.h), the cloud
// input on its own (cloud_input.h); the node's queue keeps the marker and map flush timers
// and corrected_path.
#pragma once

#include <ros/node_handle.h>
#include <tf2_ros/buffer.h>
#include <tf2_ros/transform_listener.h>

#include <memory>
#include <shared_mutex>
#include <string>

#include "autosave.h"
#include "cloud_input.h"
#include "collision_service.h"
#include "correction_service.h"
#include "fragg_map/ros/autosave_params.h"
#include "fragg_map/ros/paging_params.h"
#include "fragg_map/ros/server_params.h"
#include "frontier_publisher.h"
#include "frontier_service.h"
#include "map_publishers.h"
#include "map_services.h"
#include "octomap_compat_services.h"
#include "octomap_outputs.h"
#include "path_corrector.h"
#if FRAGG_HAVE_DYNAMIC_RECONFIGURE
#include "reconfigure.h"
#endif
#include "server_stats.h"
#include "service_threads.h"
#include "shared_map.h"
#include "submap_services.h"

namespace fragg::ros {

class MapServer {
 public:
  /// Reads and validates the parameters (throws fragg::InvalidArgument naming the bad one),
  /// builds the map and starts the parts.
  /// `map_file_arg` (the node's first argument), when not empty, overrides map_file.
  MapServer(::ros::NodeHandle& nh, ::ros::NodeHandle& private_nh,
            const std::string& map_file_arg = std::string());
  ~MapServer();

 private:
  /// The start map: the page store's, else an existing autosave, else map_file; one log line.
  void loadStartMap();
  /// The outputs that read the parameters dynamic_reconfigure changes (publishers_,
  /// octomap_outputs_), made from params_.
  void startOutputs();
  /// input_ made from params_.
  void startInput();
  /// octomap_binary / octomap_full after a cloud (`after_insert`) or any other change.
  void publishOctomaps(const ::ros::Time& stamp, bool after_insert);
  /// dynamic_reconfigure: the input and the outputs again with `next` (the input stopped
  /// first, so no cloud is half inserted), the full outputs published.
  void applyParams(const ServerParams& next);

  ServerParams params_;
  ::ros::NodeHandle nh_, private_nh_;  ///< the node's, for the parts made again by applyParams
  PagingParams paging_;                ///< paging/* (paging_params.h)
  AutosaveParams autosave_params_;     ///< autosave/*, file_root (autosave_params.h)
  std::unique_ptr<SharedMap> shared_;
  ServerStats stats_;
  tf2_ros::Buffer tf_buffer_;
  tf2_ros::TransformListener tf_listener_;
  /// Before the parts whose services and timers use its queues (they go first); its threads
  /// are stopped first of all in ~MapServer.
  ServiceThreads threads_;
  std::unique_ptr<MapPublishers> publishers_;
  std::unique_ptr<MapServices> services_;
  std::unique_ptr<OctomapCompatServices> octomap_services_;
  std::unique_ptr<OctomapOutputs> octomap_outputs_;  // only with octomap_msgs
  std::unique_ptr<CorrectionService> correction_service_;
  std::unique_ptr<SubmapServices> submap_services_;
  std::unique_ptr<CollisionService> collision_service_;
  std::unique_ptr<FrontierService> frontier_service_;
  std::unique_ptr<FrontierPublisher> frontier_publisher_;
  std::unique_ptr<PathCorrector> path_corrector_;  // only with correction/subscribe_path
  std::unique_ptr<Autosaver> autosaver_;           // only with autosave/path
  std::unique_ptr<CloudInput> input_;              // its thread uses everything above
#if FRAGG_HAVE_DYNAMIC_RECONFIGURE
  std::unique_ptr<ReconfigureServer> reconfigure_;
#endif
  /// Held shared while publishers_ / octomap_outputs_ are used from a service or the input,
  /// exclusively while applyParams replaces them.
  std::shared_mutex outputs_mutex_;
};

}  // namespace fragg::ros
