// ~truncate: check the path and the region, write the cut cells, then remove them (both under
// the write lock, so the file holds exactly what left the map). ~merge: read and check the
// file unlocked, merge under the write lock.
#include "submap_services.h"

#include <ros/console.h>

#include <chrono>
#include <optional>
#include <string>

#include "file_root.h"
#include "fragg_map/atomic_file.h"
#include "fragg_map/errors.h"
#include "fragg_map/map.h"
#include "fragg_map/ros/pose_correction.h"

namespace fragg::ros {
namespace {

using Clock = std::chrono::steady_clock;

double msSince(Clock::time_point t0) {
  return std::chrono::duration<double, std::milli>(Clock::now() - t0).count();
}

// `requested` ending in .fgm, resolved under file_root (file_root.h); throws
// fragg::InvalidArgument otherwise.
std::string fgmUnderRoot(const std::string& root, const std::string& requested) {
  const std::string ext = ".fgm";
  if (requested.size() <= ext.size() ||
      requested.compare(requested.size() - ext.size(), ext.size(), ext) != 0)
    throw fragg::InvalidArgument("unknown extension of '" + requested +
                                 "': sub-maps are .fgm files");
  return resolveUnderRoot(root, requested);
}

fragg::SubmapRegion regionOf(const fragg_map::Truncate::Request& req) {
  auto v = [](const geometry_msgs::Point& p) { return Eigen::Vector3d(p.x, p.y, p.z); };
  fragg::SubmapRegion region;
  if (req.region == fragg_map::Truncate::Request::BOX)
    region = fragg::SubmapRegion::box(v(req.min), v(req.max));
  else if (req.region == fragg_map::Truncate::Request::OUTSIDE_SPHERE)
    region = fragg::SubmapRegion::outsideSphere(v(req.center), req.radius);
  else
    throw fragg::InvalidArgument("unknown region " + std::to_string(req.region) +
                                 ": use BOX (0) or OUTSIDE_SPHERE (1)");
  region.validate();
  return region;
}

// The cells of `region` copied out of `map`.
fragg::Map copyOf(const fragg::Map& map, const fragg::SubmapRegion& region,
                  fragg::SubmapStats* st) {
  return region.kind == fragg::SubmapRegion::Kind::kBox
             ? map.extract(region.min_map, region.max_map, fragg::Backend::kCpu, st)
             : map.extractOutside(region.center_map, region.radius_m, fragg::Backend::kCpu, st);
}

// Runs `fn`; on an exception the response is cleared to success=false + message (logged,
// throttled).
template <typename Response, typename Fn>
void answerOrClear(const char* service, Response& res, Fn&& fn) {
  try {
    res.message = fn();
    res.success = true;
  } catch (const std::exception& e) {
    res = Response();
    res.success = false;
    res.message = e.what();
    ROS_WARN_THROTTLE(1.0, "fragg_map: %s refused: %s", service, e.what());
  }
}

}  // namespace

SubmapServices::SubmapServices(::ros::NodeHandle& private_nh, const ServerParams& params,
                               SharedMap* shared, std::function<void()> on_map_changed)
    : params_(params), shared_(shared), on_map_changed_(std::move(on_map_changed)) {
  truncate_ = private_nh.advertiseService("truncate", &SubmapServices::truncate, this);
  merge_ = private_nh.advertiseService("merge", &SubmapServices::merge, this);
}

bool SubmapServices::truncate(fragg_map::Truncate::Request& req,
                              fragg_map::Truncate::Response& res) {
  answerOrClear("truncate", res, [&] {
    const std::string path = fgmUnderRoot(params_.file_root, req.path);
    fragg::SubmapRegion region = regionOf(req);
    region.frame_id = params_.frame_id;
    { fragg::AtomicFile probe(path); }  // an unwritable folder fails here, map untouched
    const auto t0 = Clock::now();
    fragg::SubmapStats st;
    if (req.keep) {
      const SharedMap::ReadGuard state = shared_->read("~truncate");
      fragg::Map sub = copyOf(state->map, region, &st);
      sub.setRegion(region);
      sub.save(path);
      res.known_voxels = state->map.knownVoxelCount();
    } else {
      // The copy is written first: a failed write leaves the map as it was.
      const SharedMap::WriteGuard state = shared_->write("~truncate");
      fragg::Map sub = copyOf(state->map, region, &st);
      sub.setRegion(region);
      sub.save(path);
      fragg::SubmapStats moved;
      if (region.kind == fragg::SubmapRegion::Kind::kBox)
        state->map.truncate(region.min_map, region.max_map, fragg::Backend::kCpu, &moved);
      else
        state->map.truncateOutside(region.center_map, region.radius_m, fragg::Backend::kCpu,
                                   &moved);
      st.blocks_erased = moved.blocks_erased;
      res.known_voxels = state->map.knownVoxelCount();
    }
    res.ms = msSince(t0);
    res.cells = st.cells;
    res.blocks = st.blocks;
    res.blocks_erased = st.blocks_erased;
    return std::string(req.keep ? "copied " : "moved ") + std::to_string(st.cells) + " cells in " +
           std::to_string(st.blocks) + " blocks to " + path + "; " +
           std::to_string(res.known_voxels) + " cells left in the map";
  });
  if (res.success && !req.keep && res.cells > 0 && on_map_changed_) on_map_changed_();
  return true;
}

bool SubmapServices::merge(fragg_map::Merge::Request& req, fragg_map::Merge::Response& res) {
  answerOrClear("merge", res, [&] {
    const std::string path = fgmUnderRoot(params_.file_root, req.path);
    const fragg::MergeMode mode = fragg::mergeModeFromString(req.mode);
    std::optional<Eigen::Isometry3d> T_map_sub;
    if (req.use_transform) {
      try {
        T_map_sub = isometryFromPose(req.T_map_sub);
      } catch (const fragg::InvalidArgument& e) {
        throw fragg::InvalidArgument(std::string("T_map_sub: ") + e.what());
      }
    }
    fragg::MapParams runtime;  // only read: CPU, no kept scans
    runtime.backend = fragg::Backend::kCpu;
    const fragg::Map sub = fragg::Map::load(path, runtime);  // validates the file
    const auto t0 = Clock::now();
    const SharedMap::WriteGuard state = shared_->write("~merge");
    fragg::SubmapStats st;
    try {
      st = state->map.merge(sub, mode, T_map_sub);  // checks resolution and model first
    } catch (const fragg::InvalidArgument& e) {
      throw fragg::InvalidArgument(path + ": " + e.what());
    }
    res.ms = msSince(t0);
    res.cells = st.cells;
    res.blocks = st.blocks;
    res.known_voxels = state->map.knownVoxelCount();
    return "merged " + std::to_string(st.cells) + " cells of " + path + " (" +
           fragg::toString(mode) + "), " + std::to_string(st.blocks) + " blocks written; " +
           std::to_string(res.known_voxels) + " cells in the map";
  });
  if (res.success && res.cells > 0 && on_map_changed_) on_map_changed_();
  return true;
}

}  // namespace fragg::ros
