// Service callbacks: every exception becomes success=false with its message.
#include "map_services.h"

#include <ros/console.h>

#include <cmath>
#include <cstdio>
#include <optional>

#include "file_root.h"
#include "fragg_map/errors.h"
#include "fragg_map/map_image.h"
#include "frame_text.h"
#include "map_copy.h"
#include "map_file_loader.h"
#include "process_memory.h"
#if FRAGG_HAVE_OCTOMAP
#include "fragg_map/interop/octomap_io.h"
#endif

namespace fragg::ros {
namespace {

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

MapServices::MapServices(::ros::NodeHandle& private_nh, ServiceThreads* threads,
                         const ServerParams& params, SharedMap* shared, ServerStats* stats,
                         std::function<void()> on_map_replaced)
    : params_(params),
      shared_(shared),
      stats_(stats),
      on_map_replaced_(std::move(on_map_replaced)) {
  ::ros::NodeHandle save_nh = threads->handle(private_nh, "save_map");
  ::ros::NodeHandle load_nh = threads->handle(private_nh, "load_map");
  ::ros::NodeHandle edit_nh = threads->handle(private_nh, "map_edits");
  ::ros::NodeHandle stats_nh = threads->handle(private_nh, "get_stats");
  save_ = save_nh.advertiseService("save_map", &MapServices::saveMap, this);
  load_ = load_nh.advertiseService("load_map", &MapServices::loadMap, this);
  reset_ = edit_nh.advertiseService("reset_map", &MapServices::reset, this);
  clear_ = edit_nh.advertiseService("clear_bbox", &MapServices::clearBox, this);
  stats_srv_ = stats_nh.advertiseService("get_stats", &MapServices::getStats, this);
}

bool MapServices::saveMap(fragg_map::SaveMap::Request& req, fragg_map::SaveMap::Response& res) {
  return answer("save_map", res, [&] {
    const std::string path = resolveUnderRoot(params_.file_root, req.path);
    const auto saved = [&](size_t known) {
      return "saved " + std::to_string(known) + " known voxels to " + path;
    };
    if (endsWith(path, ".fgm")) {
      // As the autosave: a memory copy under the read lock, compression and disk without it
      // (insertion waits for the copy only). A paged map has no image: its save reads the
      // paged-out blocks from the store, under the lock.
      fragg::MapImage image;
      size_t known = 0;
      {
        const SharedMap::ReadGuard state = shared_->read("~save_map");
        known = state->map.knownVoxelCount();
        if (state->map.paging()) {
          state->map.save(path);
          return saved(known);
        }
        image = state->map.image();
      }
      fragg::writeMapImage(image, path);
      return saved(known);
    }
    if (!endsWith(path, ".bt"))
      throw fragg::InvalidArgument("unknown extension of '" + path + "': use .fgm or .bt");
#if FRAGG_HAVE_OCTOMAP
    // A copy of the observed cells under the read lock (insertion waits for the copy only);
    // the tree is built and written from the copy. A paged map has no whole copy in RAM: its
    // export reads the resident blocks under the lock.
    std::optional<fragg::Map> copy;
    {
      const SharedMap::ReadGuard state = shared_->read("~save_map");
      if (state->map.paging()) {
        fragg::exportOctomap(state->map, path);
        return saved(state->map.knownVoxelCount());
      }
      copy.emplace(observedCopy(state->map));
    }
    fragg::exportOctomap(*copy, path);
    return saved(copy->knownVoxelCount());
#else
    throw fragg::InvalidArgument("this build has no liboctomap: .bt is not available");
#endif
  });
}

std::string MapServices::loadMap(const std::string& path) {
  // Validates the whole file before the map is touched.
  fragg::Map loaded = loadMapFile(path, params_.map);
  std::string message;
  {
    const SharedMap::WriteGuard state = shared_->write("~load_map");
    state->map = std::move(loaded);
    state->stamps.rebuild(state->map.scanStore());
    stats_->restart(state->map.scanCount());
    message = "loaded " + std::to_string(state->map.blockCount()) + " blocks and " +
              std::to_string(state->map.scanStore().size()) + " kept scans from " + path;
  }
  releaseFreeHeap();  // the replaced map's memory
  if (on_map_replaced_) on_map_replaced_();
  return message;
}

std::string MapServices::resetMap() {
  const size_t rss_before = residentBytes();
  {
    // A new map rather than Map::reset(), which keeps its block storage for reuse.
    const SharedMap::WriteGuard state = shared_->write("~reset");
    state->map = fragg::Map(params_.map);  // as MapServer builds it
    state->stamps.clear();
    stats_->restart(0);
  }
  releaseFreeHeap();
  const size_t rss_after = residentBytes();
  if (on_map_replaced_) on_map_replaced_();
  char note[128];
  std::snprintf(note, sizeof(note), "map reset; resident memory %.1f -> %.1f MiB",
                rss_before / 1048576.0, rss_after / 1048576.0);
  ROS_INFO("fragg_map: %s", note);
  return note;
}

std::string MapServices::clearBox(const Eigen::Vector3d& min_m, const Eigen::Vector3d& max_m) {
  std::string message;
  {
    const SharedMap::WriteGuard state = shared_->write("~clear_bbox");
    const size_t before = state->map.blockCount();
    state->map.clearBox(min_m, max_m);  // validates the box first
    message = "cleared; blocks " + std::to_string(before) + " -> " +
              std::to_string(state->map.blockCount());
  }
  if (on_map_replaced_) on_map_replaced_();
  return message;
}

std::string MapServices::freeBox(const Eigen::Vector3d& min_m, const Eigen::Vector3d& max_m) {
  uint64_t cells = 0;
  {
    const SharedMap::WriteGuard state = shared_->write("~clear_bbx");
    cells = state->map.freeBox(min_m, max_m);  // validates the box first
  }
  if (on_map_replaced_) on_map_replaced_();
  return "set " + std::to_string(cells) + " known cells free";
}

bool MapServices::loadMap(fragg_map::LoadMap::Request& req, fragg_map::LoadMap::Response& res) {
  return answer("load_map", res,
                [&] { return loadMap(resolveUnderRoot(params_.file_root, req.path)); });
}

bool MapServices::reset(fragg_map::Reset::Request&, fragg_map::Reset::Response& res) {
  return answer("reset_map", res, [&] { return resetMap(); });
}

bool MapServices::clearBox(fragg_map::ClearBox::Request& req, fragg_map::ClearBox::Response& res) {
  return answer("clear_bbox", res, [&] { return clearBox(toEigen(req.min), toEigen(req.max)); });
}

bool MapServices::getStats(fragg_map::GetStats::Request&, fragg_map::GetStats::Response& res) {
  return answer("get_stats", res, [&] {
    const SharedMap::ReadGuard state = shared_->read("~get_stats");
    res.stats = stats_->toMsg(state->map, params_.frame_id, ::ros::Time::now());
    return std::string("ok");
  });
}

}  // namespace fragg::ros
