// Service callbacks: every exception becomes success=false with its message.
#include "map_services.h"

#include <ros/console.h>

#include <cmath>

#include "fragg_map/errors.h"
#if FRAGG_HAVE_OCTOMAP
#include "fragg_map/interop/octomap_io.h"
#endif

namespace fragg::ros {
namespace {

bool endsWith(const std::string& s, const std::string& suffix) {
  return s.size() >= suffix.size() &&
         s.compare(s.size() - suffix.size(), suffix.size(), suffix) == 0;
}

// Runs `fn`, turning any exception into success=false + message (logged, throttled).
template <typename Response, typename Fn>
bool answer(const char* service, Response& res, Fn&& fn) {
  try {
    res.message = fn();
    res.success = true;
  } catch (const std::exception& e) {
    res.success = false;
    res.message = e.what();
    ROS_WARN_THROTTLE(1.0, "fragg_map: %s refused: %s", service, e.what());
  }
  return true;  // the answer itself carries the failure
}

Eigen::Vector3d toEigen(const geometry_msgs::Point& p) { return {p.x, p.y, p.z}; }

}  // namespace

MapServices::MapServices(::ros::NodeHandle& private_nh, const ServerParams& params,
                         SharedMap* shared, ServerStats* stats,
                         std::function<void()> on_map_replaced)
    : params_(params),
      shared_(shared),
      stats_(stats),
      on_map_replaced_(std::move(on_map_replaced)) {
  save_ = private_nh.advertiseService("save_map", &MapServices::saveMap, this);
  load_ = private_nh.advertiseService("load_map", &MapServices::loadMap, this);
  reset_ = private_nh.advertiseService("reset", &MapServices::reset, this);
  clear_ = private_nh.advertiseService("clear_bbox", &MapServices::clearBox, this);
  stats_srv_ = private_nh.advertiseService("get_stats", &MapServices::getStats, this);
}

bool MapServices::saveMap(fragg_map::SaveMap::Request& req, fragg_map::SaveMap::Response& res) {
  return answer("save_map", res, [&] {
    const std::string& path = req.path;
    if (path.empty()) throw fragg::InvalidArgument("empty path");
    const SharedMap::ReadGuard state = shared_->read();  // saving only reads the map
    if (endsWith(path, ".fgm")) {
      state->map.save(path);
    } else if (endsWith(path, ".bt")) {
#if FRAGG_HAVE_OCTOMAP
      fragg::exportOctomap(state->map, path);
#else
      throw fragg::InvalidArgument("this build has no liboctomap: .bt is not available");
#endif
    } else {
      throw fragg::InvalidArgument("unknown extension of '" + path + "': use .fgm or .bt");
    }
    return "saved " + std::to_string(state->map.knownVoxelCount()) + " known voxels to " + path;
  });
}

bool MapServices::loadMap(fragg_map::LoadMap::Request& req, fragg_map::LoadMap::Response& res) {
  const bool ok = answer("load_map", res, [&] {
    if (!endsWith(req.path, ".fgm"))
      throw fragg::InvalidArgument("unknown extension of '" + req.path + "': load_map reads .fgm");
    // The file gives resolution, occupancy model and kept scans; the server's own settings
    // (backend, threads, ray cast, scan store budget...) the rest. Validates first.
    fragg::Map loaded = fragg::Map::load(req.path, params_.map);
    if (std::abs(loaded.resolution() - params_.map.resolution_m) > 1e-12)
      throw fragg::InvalidArgument("the file's resolution " + std::to_string(loaded.resolution()) +
                                   " m differs from the server's " +
                                   std::to_string(params_.map.resolution_m) + " m");
    const SharedMap::WriteGuard state = shared_->write();
    state->map = std::move(loaded);
    state->stamps.rebuild(state->map.scanStore());
    return "loaded " + std::to_string(state->map.blockCount()) + " blocks and " +
           std::to_string(state->map.scanStore().size()) + " kept scans from " + req.path;
  });
  if (res.success && on_map_replaced_) on_map_replaced_();
  return ok;
}

bool MapServices::reset(fragg_map::Reset::Request&, fragg_map::Reset::Response& res) {
  answer("reset", res, [&] {
    const SharedMap::WriteGuard state = shared_->write();
    state->map.reset();
    state->stamps.clear();
    stats_->clearInsertions();
    return std::string("map reset");
  });
  if (res.success && on_map_replaced_) on_map_replaced_();
  return true;
}

bool MapServices::clearBox(fragg_map::ClearBox::Request& req, fragg_map::ClearBox::Response& res) {
  answer("clear_bbox", res, [&] {
    const SharedMap::WriteGuard state = shared_->write();
    const size_t before = state->map.blockCount();
    state->map.clearBox(toEigen(req.min), toEigen(req.max));  // validates the box first
    return "cleared; blocks " + std::to_string(before) + " -> " +
           std::to_string(state->map.blockCount());
  });
  if (res.success && on_map_replaced_) on_map_replaced_();
  return true;
}

bool MapServices::getStats(fragg_map::GetStats::Request&, fragg_map::GetStats::Response& res) {
  return answer("get_stats", res, [&] {
    const SharedMap::ReadGuard state = shared_->read();
    res.stats = stats_->toMsg(state->map, params_.frame_id, ::ros::Time::now());
    return std::string("ok");
  });
}

}  // namespace fragg::ros
