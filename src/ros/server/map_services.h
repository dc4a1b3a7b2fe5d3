// The map server's services on the private handle: ~save_map (.fgm or .bt by extension),
// ~load_map, ~reset, ~clear_bbox, ~get_stats. Each answers success + message; a bad request
// (unknown extension, unwritable path, missing file, inverted or NaN box) answers
// success=false with the reason and leaves the map unchanged. Nothing escapes a callback.
#pragma once

#include <ros/node_handle.h>
#include <ros/service_server.h>

#include <functional>
#include <string>

#include "fragg_map/ClearBox.h"
#include "fragg_map/GetStats.h"
#include "fragg_map/LoadMap.h"
#include "fragg_map/Reset.h"
#include "fragg_map/SaveMap.h"
#include "fragg_map/ros/server_params.h"
#include "server_stats.h"
#include "shared_map.h"

namespace fragg::ros {

class MapServices {
 public:
  /// `on_map_replaced` runs (map unlocked) after reset, load and clear_bbox.
  MapServices(::ros::NodeHandle& private_nh, const ServerParams& params, SharedMap* shared,
              ServerStats* stats, std::function<void()> on_map_replaced);

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
