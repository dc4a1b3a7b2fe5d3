// Wiring of the map server's parts.
#include "map_server.h"

#include <ros/console.h>

#include <optional>
#include <string>
#include <utility>

#include "file_root.h"
#include "fragg_map/log.h"
#include "fragg_map/ros/publish_buffers.h"
#include "octomap_compat_notes.h"

namespace fragg::ros {

MapServer::MapServer(::ros::NodeHandle& nh, ::ros::NodeHandle& private_nh,
                     const std::string& map_file_arg)
    : params_(readParameters(private_nh)), tf_listener_(tf_buffer_, nh) {
  // Should a part throw (the node does not start), the service threads stop before the parts
  // built so far (whose callbacks they may be running) are destroyed.
  struct StopThreadsOnThrow {
    ServiceThreads* threads;
    bool armed = true;
    ~StopThreadsOnThrow() {
      if (armed) threads->stop();
    }
  } stop_on_throw{&threads_};
  if (!map_file_arg.empty()) params_.octomap.map_file = map_file_arg;
  logOctomapCompatNotes(params_);
  // Each publication's serialised buffer reuses the last one's pages (publish_buffers.h).
  if (!keepPublicationBuffers(kKeptPublicationBytes))
    ROS_WARN("fragg_map: malloc thresholds not raised: each publication maps fresh pages");
  // Throws (the node does not start) when the folder cannot be created.
  params_.file_root =
      prepareFileRoot(params_.file_root.empty() ? defaultFileRoot() : params_.file_root);
  ROS_INFO("fragg_map: file services read and write under file_root %s", params_.file_root.c_str());
  fragg::setLogSink([](fragg::LogLevel level, const std::string& line) {
    if (level == fragg::LogLevel::kWarning)
      ROS_WARN("fragg_map: %s", line.c_str());
    else
      ROS_INFO("fragg_map: %s", line.c_str());
  });
  paging_ = readPagingParameters(private_nh, &params_.map);
  {
    XmlRpc::XmlRpcValue root;  // stays invalid (every default) when the namespace holds nothing
    private_nh.getParam(private_nh.getNamespace(), root);
    autosave_params_ = parseAutosaveParameters(root);
  }
  shared_ = std::make_unique<SharedMap>(MapState(makeServerMap(params_.map, paging_)));
  nh_ = nh;
  private_nh_ = private_nh;
  // The outputs stay on the node's own queue (with the reconfigure server, which makes them
  // again): a callback of theirs cannot run while applyParams replaces them.
  startOutputs();
  services_ =
      std::make_unique<MapServices>(private_nh, &threads_, params_, shared_.get(), &stats_, [this] {
        const std::shared_lock<std::shared_mutex> outputs(outputs_mutex_);
        publishers_->publishFull(::ros::Time::now());
        publishOctomaps(::ros::Time::now(), false);
      });
  ::ros::NodeHandle edit_nh = threads_.handle(private_nh, "map_edits");
  octomap_services_ = std::make_unique<OctomapCompatServices>(edit_nh, services_.get(),
                                                              params_.octomap.clear_bbx_free);
  loadStartMap();  // throws (the node does not start) when a file is unreadable
  auto publish_changed = [this] {
    try {
      const std::shared_lock<std::shared_mutex> outputs(outputs_mutex_);
      publishers_->publishAfterCorrection(::ros::Time::now());
      publishOctomaps(::ros::Time::now(), false);
    } catch (const std::exception& e) {
      ROS_ERROR_THROTTLE(5.0, "fragg_map: publishing failed: %s", e.what());
    }
  };
  ::ros::NodeHandle correct_nh = threads_.handle(private_nh, "correct_poses");
  correction_service_ = std::make_unique<CorrectionService>(correct_nh, params_, shared_.get(),
                                                            &stats_, publish_changed);
  ::ros::NodeHandle submap_nh = threads_.handle(private_nh, "submaps");
  submap_services_ =
      std::make_unique<SubmapServices>(submap_nh, params_, shared_.get(), publish_changed);
  ::ros::NodeHandle collision_nh = threads_.handle(nh, "check_collision");
  ::ros::NodeHandle collision_private_nh = threads_.handle(private_nh, "check_collision");
  collision_service_ = std::make_unique<CollisionService>(
      collision_nh, collision_private_nh, params_, tf_buffer_, shared_.get(), &stats_);
  ::ros::NodeHandle frontier_nh = threads_.handle(private_nh, "get_frontiers");
  frontier_service_ =
      std::make_unique<FrontierService>(frontier_nh, params_, tf_buffer_, shared_.get(), &stats_);
  ::ros::NodeHandle frontier_topics_nh = threads_.handle(nh, "frontier_topics");
  frontier_publisher_ =
      std::make_unique<FrontierPublisher>(frontier_topics_nh, params_, shared_.get(), &stats_);
  if (params_.correction.subscribe_path)
    path_corrector_ = std::make_unique<PathCorrector>(nh, params_, tf_buffer_, shared_.get(),
                                                      &stats_, publish_changed);
  startInput();
#if FRAGG_HAVE_DYNAMIC_RECONFIGURE
  reconfigure_ = std::make_unique<ReconfigureServer>(
      private_nh, params_, [this](const ServerParams& next) { applyParams(next); });
#endif
  if (autosave_params_.enabled()) {
    autosaver_ = std::make_unique<Autosaver>(autosave_params_, shared_.get());
    if (autosave_params_.period_s > 0)
      ROS_INFO("fragg_map: autosave to %s every %.1f s and on shutdown",
               autosave_params_.path.c_str(), autosave_params_.period_s);
    else
      ROS_INFO("fragg_map: autosave to %s on shutdown", autosave_params_.path.c_str());
  }
  publishers_->publishFull(::ros::Time::now());
  {
    const SharedMap::ReadGuard state = shared_->read("start-up");
    ROS_INFO("fragg_map: %s map at %.3f m in '%s', backend %s (%s), sensor %s, queue %d",
             params_.latch ? "latched" : "unlatched", params_.map.resolution_m,
             params_.frame_id.c_str(), state->map.backendName(), state->map.backendReason().c_str(),
             params_.sensor.describe().c_str(), params_.queue_size);
  }
  if (!paging_.store.empty()) {
    const SharedMap::ReadGuard state = shared_->read("start-up");
    const fragg::PagingStats paging = state->map.pagingStats();
    ROS_INFO(
        "fragg_map: paging to %s (budget %.0f MB, radius %.1f m): %zu scans and %lu "
        "blocks continued from it",
        paging.store.c_str(), paging_.policy.budget_mb, paging_.policy.radius_m,
        state->map.scanCount(), static_cast<unsigned long>(paging.paged_blocks));
    stats_.restart(state->map.scanCount());  // the clouds in the map: the store's, then ours
  }
  const fragg::ScanStoreParams& scans = params_.map.scans;
  if (scans.keep) {
    const std::string budget =
        scans.max_bytes ? std::to_string(scans.max_bytes >> 20) + " MiB" : std::string("none");
    const std::string beyond =
        scans.spill_dir.empty() ? "the oldest points dropped" : "spilled to " + scans.spill_dir;
    ROS_INFO("fragg_map: keeping scans for ~correct_poses%s (budget %s; beyond it %s)",
             params_.correction.subscribe_path ? " and corrected_path" : "", budget.c_str(),
             beyond.c_str());
  }
  stop_on_throw.armed = false;
}

void MapServer::loadStartMap() {
  // What the map starts from: a page store > an autosave > map_file (docs/ros.md).
  const std::string& map_file = params_.octomap.map_file;
  if (!paging_.store.empty()) {
    if (autosave_params_.enabled())
      ROS_WARN(
          "fragg_map: autosave/path %s ignored: paging/store %s is the map (committed every "
          "paging/commit_every_s)",
          autosave_params_.path.c_str(), paging_.store.c_str());
    autosave_params_ = AutosaveParams();
    if (!map_file.empty())
      ROS_INFO("fragg_map: map_file: %s", services_->loadMap(map_file).c_str());
    return;  // the paging line below says what the store held
  }
  if (autosave_params_.enabled()) {
    std::optional<fragg::Map> saved = loadAutosave(autosave_params_.path, params_.map);
    if (saved) {
      const size_t scans = saved->scanCount(), blocks = saved->blockCount();
      {
        const SharedMap::WriteGuard state = shared_->write("autosave load");
        state->map = std::move(*saved);
        state->stamps.rebuild(state->map.scanStore());
        stats_.restart(state->map.scanCount());
      }
      ROS_INFO("fragg_map: start map: autosave %s (%zu scans, %zu blocks)%s",
               autosave_params_.path.c_str(), scans, blocks,
               map_file.empty() ? "" : "; map_file not loaded (the autosave is newer)");
      return;
    }
  }
  if (!map_file.empty()) {
    ROS_INFO("fragg_map: start map: map_file: %s", services_->loadMap(map_file).c_str());
  } else {
    const std::string note =
        autosave_params_.enabled() ? " (no autosave at " + autosave_params_.path + " yet)" : "";
    ROS_INFO("fragg_map: start map: empty%s", note.c_str());
  }
}

void MapServer::startOutputs() {
  publishers_ = std::make_unique<MapPublishers>(nh_, private_nh_, params_, shared_.get(), &stats_);
#if FRAGG_HAVE_OCTOMAP_MSGS
  octomap_outputs_ = std::make_unique<OctomapOutputs>(nh_, params_, shared_.get());
#endif
}

void MapServer::publishOctomaps(const ::ros::Time& stamp, bool after_insert) {
  // Without octomap_msgs there is no OctomapOutputs to call (nor its code to link). After a
  // cloud map_rate applies; after reset, load, clear and corrections they go out at once.
#if FRAGG_HAVE_OCTOMAP_MSGS
  if (!octomap_outputs_) return;
  if (after_insert)
    octomap_outputs_->publishAfterInsert(stamp);
  else
    octomap_outputs_->publish(stamp);
#else
  (void)stamp;
  (void)after_insert;
#endif
}

void MapServer::startInput() {
  input_ = std::make_unique<CloudInput>(
      nh_, params_, tf_buffer_, shared_.get(), &stats_,
      [this](const sensor_msgs::PointCloud2& msg, const fragg::SensorModel& sensor,
             const Eigen::Isometry3d& T_map_sensor, PublishTimes* times) {
        try {
          const std::shared_lock<std::shared_mutex> outputs(outputs_mutex_);
          publishers_->publishAfterInsert(msg, sensor, T_map_sensor, times);
          publishOctomaps(msg.header.stamp, true);
        } catch (const std::exception& e) {
          ROS_ERROR_THROTTLE(5.0, "fragg_map: publishing failed: %s", e.what());
        }
      },
      [this] {
        const std::shared_lock<std::shared_mutex> outputs(outputs_mutex_);
        publishers_->betweenClouds();
      });
}

void MapServer::applyParams(const ServerParams& next) {
  input_.reset();  // its thread publishes under the shared lock: stopped before taking it
  {
    const std::unique_lock<std::shared_mutex> outputs(outputs_mutex_);
#if FRAGG_HAVE_OCTOMAP_MSGS
    octomap_outputs_.reset();
#endif
    publishers_.reset();  // its topics go before the new ones are advertised
    params_ = next;
    startOutputs();
    publishers_->publishFull(::ros::Time::now());
    publishOctomaps(::ros::Time::now(), false);
  }
  startInput();
}

MapServer::~MapServer() {
#if FRAGG_HAVE_DYNAMIC_RECONFIGURE
  reconfigure_.reset();  // no change arrives while the parts go
#endif
  threads_.stop();     // no service or timer callback runs from here on
  input_.reset();      // stop the insertion thread before the rest goes
  autosaver_.reset();  // then the last save
  fragg::setLogSink(fragg::LogSink());
}

}  // namespace fragg::ros
