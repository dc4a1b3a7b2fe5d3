// The map server's services on the private handle: ~save_map (.fgm or .bt by extension),
// ~load_map (.fgm, .bt or .ot), ~reset_map, ~clear_bbox, ~get_stats (octomap_server's ~reset and
// ~clear_bbx: octomap_compat_services.h, through resetMap() and clearBox()). Each answers success +
// message; a bad request (unknown extension, unwritable path, missing file, inverted or NaN box)
// answers success=false with the reason and leaves the map unchanged. Nothing escapes a callback.
// ~save_map and ~load_map paths are confined to params.file_root (file_root.h); loadMap(path),
// the start-up map_file's way in, is not. ~save_map of a .fgm holds the read lock only for the
// map's copy (Map::image) and compresses and writes it (writeMapImage) without the lock, as the
// autosave does; a .bt is exported from a copy of the map's cells (Map::extract of its observed
// bounds) taken under the read lock; a paged map (no image, no whole copy) is written under it.
// Threads (service_threads.h): ~get_stats, ~save_map, ~load_map and the edits (~reset_map,
// ~clear_bbox) each have a callback queue and thread of their own, so that a long save never
// holds ~get_stats back.
#pragma once

#include <ros/node_handle.h>
#include <ros/service_server.h>

#include <Eigen/Core>
#include <functional>
#include <string>

#include "fragg_map/ClearBox.h"
#include "fragg_map/GetStats.h"
#include "fragg_map/LoadMap.h"
#include "fragg_map/Reset.h"
#include "fragg_map/SaveMap.h"
#include "fragg_map/ros/server_params.h"
#include "server_stats.h"
#include "service_threads.h"
#include "shared_map.h"

namespace fragg::ros {

class MapServices {
 public:
  /// `on_map_replaced` runs (map unlocked) after reset, load and clear_bbox. The services are
  /// advertised on private_nh's namespace, on queues of `threads` (which must outlive them).
  MapServices(::ros::NodeHandle& private_nh, ServiceThreads* threads, const ServerParams& params,
              SharedMap* shared, ServerStats* stats, std::function<void()> on_map_replaced);

  /// Replaces the map by an empty one (the old one's memory goes back to the system), zeroes
  /// the statistics and republishes. Returns what it did (resident memory before and after).
  std::string resetMap();
  /// Makes the cells in [min, max] unknown (throws fragg::InvalidArgument for a bad box, map
  /// untouched) and republishes. Returns what it did.
  std::string clearBox(const Eigen::Vector3d& min_m, const Eigen::Vector3d& max_m);
  /// Sets the observed cells in [min, max] free at the lower clamp, octomap_server's clear_bbx
  /// rule (throws fragg::InvalidArgument for a bad box, map untouched), and republishes.
  /// Returns what it did.
  std::string freeBox(const Eigen::Vector3d& min_m, const Eigen::Vector3d& max_m);
  /// Replaces the map by the one in `path` (map_file_loader.h), restarts the statistics from
  /// the file's scan count and republishes. Throws as loadMapFile does (map untouched).
  std::string loadMap(const std::string& path);

 private:
  bool saveMap(fragg_map::SaveMap::Request& req, fragg_map::SaveMap::Response& res);
  bool loadMap(fragg_map::LoadMap::Request& req, fragg_map::LoadMap::Response& res);
  bool reset(fragg_map::Reset::Request& req, fragg_map::Reset::Response& res);
  bool clearBox(fragg_map::ClearBox::Request& req, fragg_map::ClearBox::Response& res);
  bool getStats(fragg_map::GetStats::Request& req, fragg_map::GetStats::Response& res);

  const ServerParams params_;
  SharedMap* shared_;
  ServerStats* stats_;
  std::function<void()> on_map_replaced_;
  ::ros::ServiceServer save_, load_, reset_, clear_, stats_srv_;
};

}  // namespace fragg::ros
