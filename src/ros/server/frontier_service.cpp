// ~get_frontiers: validate, place the robot, compute under the read lock, answer.
#include "frontier_service.h"

#include <ros/console.h>
#include <tf2/exceptions.h>
#include <tf2_eigen/tf2_eigen.h>

#include <algorithm>
#include <chrono>
#include <cmath>
#include <optional>
#include <vector>

#include "fragg_map/errors.h"
#include "fragg_map/planning/coarse_map.h"
#include "fragg_map/planning/query_control.h"
#include "map_copy.h"

namespace fragg::ros {
namespace {

geometry_msgs::Point toPoint(const Eigen::Vector3d& v) {
  geometry_msgs::Point p;
  p.x = v.x(), p.y = v.y(), p.z = v.z();
  return p;
}

Eigen::Vector3d fromPoint(const geometry_msgs::Point& p) { return Eigen::Vector3d(p.x, p.y, p.z); }

fragg_map::FrontierCluster clusterMsg(const planning::FrontierCluster& c,
                                      const std::vector<planning::Viewpoint>& views) {
  fragg_map::FrontierCluster m;
  m.id = c.id;
  m.cells = c.cells.size();
  m.centroid = toPoint(c.centroid_m);
  m.min = toPoint(c.min_m);
  m.max = toPoint(c.max_m);
  m.direction.x = c.direction.x(), m.direction.y = c.direction.y();
  m.direction.z = c.direction.z();
  for (const planning::Viewpoint& v : views) {
    geometry_msgs::Pose pose;
    pose.position = toPoint(v.position_m);
    pose.orientation.z = std::sin(0.5 * v.yaw_rad);
    pose.orientation.w = std::cos(0.5 * v.yaw_rad);
    m.viewpoints.push_back(pose);
    m.gains_bits.push_back(v.gain_bits);
    m.distances_m.push_back(v.distance_m);
    m.scores.push_back(v.score);
  }
  return m;
}

// Runs a library check; its InvalidArgument comes back naming the request field.
template <typename Fn>
void asField(const std::string& field, Fn&& fn) {
  try {
    fn();
  } catch (const fragg::InvalidArgument& e) {
    throw fragg::InvalidArgument(field + ": " + e.what());
  }
}

planning::GainSensor sensorFrom(const fragg_map::GetFrontiers::Request& req,
                                const planning::GainSensor& configured) {
  planning::GainSensor s = configured;
  if (req.sensor == "pinhole") {
    s = planning::GainSensor();
  } else if (req.sensor == "lidar") {
    s = planning::GainSensor();
    s.kind = planning::GainSensor::Kind::kLidar;
    s.columns = 360;  // as `fragg_map frontiers --sensor lidar`
    s.rows = 16;
  } else if (!req.sensor.empty()) {
    throw fragg::InvalidArgument("sensor must be \"\", pinhole or lidar, got '" + req.sensor + "'");
  }
  const auto pair = [](const char* name, size_t n) {
    if (n != 0 && n != 2)
      throw fragg::InvalidArgument(std::string(name) + " takes 0 or 2 values, got " +
                                   std::to_string(n));
    return n == 2;
  };
  if (pair("rays", req.rays.size())) s.columns = req.rays[0], s.rows = req.rays[1];
  if (pair("fov", req.fov.size()))
    s.horizontal_fov_rad = req.fov[0], s.vertical_fov_rad = req.fov[1];
  if (pair("elevation", req.elevation.size()))
    s.min_elevation_rad = req.elevation[0], s.max_elevation_rad = req.elevation[1];
  if (std::isnan(req.max_range) || req.max_range < 0.0)
    throw fragg::InvalidArgument("max_range must be > 0 (0: keep), got " +
                                 std::to_string(req.max_range));
  if (req.max_range > 0.0) s.max_range_m = req.max_range;
  asField("sensor", [&] { s.validate(); });
  return s;
}

}  // namespace

FrontierService::FrontierService(::ros::NodeHandle& private_nh, const ServerParams& params,
                                 const tf2_ros::Buffer& tf, SharedMap* shared, ServerStats* stats)
    : params_(params), tf_(tf), shared_(shared), stats_(stats) {
  service_ = private_nh.advertiseService("get_frontiers", &FrontierService::get, this);
}

FrontierService::Query FrontierService::queryFrom(const fragg_map::GetFrontiers::Request& req,
                                                  const FrontierParams& p) {
  Query q;
  if (req.k < 1)
    throw fragg::InvalidArgument("k (viewpoints per cluster) must be >= 1, got " +
                                 std::to_string(req.k));
  if (req.min_cluster < 0)
    throw fragg::InvalidArgument(
        "min_cluster must be >= 1 (0: the frontiers/min_cluster "
        "parameter), got " +
        std::to_string(req.min_cluster));
  q.filter = p.filter;
  if (req.use_box) {
    q.filter.use_box = true;
    q.filter.box_min_m = fromPoint(req.box_min);
    q.filter.box_max_m = fromPoint(req.box_max);
  }
  asField("box", [&] { q.filter.validate(); });
  q.clusters = p.clusters;
  if (req.min_cluster > 0) q.clusters.min_cells = static_cast<uint64_t>(req.min_cluster);
  q.clusters.validate();
  q.views = p.views;
  q.views.top_k = req.k;
  q.views.sensor = sensorFrom(req, p.views.sensor);
  if (req.use_robot_position && !req.robot_frame.empty())
    throw fragg::InvalidArgument("give robot_position or robot_frame, not both");
  if (req.use_robot_position) {
    q.views.robot_m = fromPoint(req.robot_position);
    if (!q.views.robot_m->allFinite())
      throw fragg::InvalidArgument("robot_position must be finite");
  }
  q.views.validate();
  return q;
}

int FrontierService::autoCoarseCells(const MapState& state, std::string* note) const {
  const std::optional<planning::BeamSpacing> beams = state.beams.estimate();
  if (!beams) {
    *note = ", map cells: no LiDAR beam spacing known yet";
    return 1;
  }
  double range_m = beams->range_m;
  if (params_.sensor.max_range_m > 0.0) range_m = std::min(range_m, params_.sensor.max_range_m);
  const int cells =
      planning::coarseCellsForBeams(state.map.resolution(), beams->angle_rad, range_m);
  char buf[96];
  std::snprintf(buf, sizeof buf, ", from beams %.2f deg apart at %.0f m",
                beams->angle_rad * 57.29578, range_m);
  *note = buf;
  return cells;
}

Eigen::Vector3d FrontierService::robotPosition(const std::string& frame_in) const {
  const std::string frame = !frame_in.empty() && frame_in[0] == '/' ? frame_in.substr(1) : frame_in;
  if (frame == params_.frame_id) return Eigen::Vector3d::Zero();
  std::string error;
  try {
    if (tf_.canTransform(params_.frame_id, frame, ::ros::Time(0), &error))
      return tf2::transformToEigen(tf_.lookupTransform(params_.frame_id, frame, ::ros::Time(0)))
          .translation();
  } catch (const tf2::TransformException& e) {
    error = e.what();
  }
  throw fragg::InvalidArgument("robot_frame: no transform from '" + frame + "' to '" +
                               params_.frame_id + "' now: " + error);
}

bool FrontierService::get(fragg_map::GetFrontiers::Request& req,
                          fragg_map::GetFrontiers::Response& res) {
  res = fragg_map::GetFrontiers::Response();
  try {
    Query q = queryFrom(req, params_.frontiers);
    if (!req.robot_frame.empty()) q.views.robot_m = robotPosition(req.robot_frame);

    const auto t0 = std::chrono::steady_clock::now();
    std::vector<VoxelKey> cells;
    std::vector<planning::FrontierCluster> clusters;
    std::vector<std::vector<planning::Viewpoint>> views;
    // frontiers/deadline_s: the query stops (QueryStopped) once it passed.
    std::optional<planning::QueryControl> deadline;
    if (params_.frontiers.deadline_s > 0.0)
      deadline = planning::QueryControl::within(params_.frontiers.deadline_s);
    const planning::QueryControl* control = deadline ? &*deadline : nullptr;
    // frontiers/coarse_cells 0: from the LiDAR's beam spacing (MapState::beams).
    if (req.coarse_cells != 0 && !planning::validCoarseCells(req.coarse_cells))
      throw fragg::InvalidArgument("coarse_cells must be 0 (the parameter), 1, 2, 4 or 8, got " +
                                   std::to_string(req.coarse_cells));
    std::optional<planning::ViewpointGain> gain = params_.frontiers.gain;
    if (!req.gain.empty())
      asField("gain", [&] { gain = planning::viewpointGainFromName(req.gain); });
    int coarse_cells = req.coarse_cells != 0 ? req.coarse_cells : params_.frontiers.coarse_cells;
    std::string grid_note;
    const auto answer = [&](const Map& map) {
      cells = planning::findFrontierCells(map, q.filter, params_.map.threads, control);
      planning::FrontierClusterer clusterer(q.clusters);
      clusters = clusterer.cluster(map, cells, control);
      views = planning::clustersViewpoints(map, clusters, q.views, params_.map.threads, control);
    };
    // The query runs on a copy: the coarse state map (coarse_cells > 1; with a box, the box and
    // the query's reach only), else the observed cells as they are (map_copy.h: the same answer,
    // the entropy of cells in the unknown band included). The map's read lock is held only while
    // the copy is made: insertion and the other services go on meanwhile.
    std::optional<Map> copy;
    {
      const SharedMap::ReadGuard state = shared_->read("~get_frontiers");
      res.revision = state->map.revision();
      if (coarse_cells == 0) coarse_cells = autoCoarseCells(*state, &grid_note);
      q.views.gain = gain               ? *gain
                     : coarse_cells > 1 ? planning::ViewpointGain::kCoverage
                                        : planning::ViewpointGain::kEntropy;
      if (coarse_cells > 1) {
        if (q.filter.use_box)  // only what a query in the box sees: the same answer
          copy.emplace(planning::coarseStateMapIn(
              state->map, coarse_cells, q.filter.box_min_m, q.filter.box_max_m,
              q.filter.min_obstacle_distance_m + planning::viewpointReachM(q.views), control));
        else
          copy.emplace(planning::coarseStateMap(state->map, coarse_cells, control));
      } else {
        copy.emplace(observedCopy(state->map));
      }
    }
    answer(*copy);
    const bool coarse = coarse_cells > 1;
    res.ms =
        std::chrono::duration<double, std::milli>(std::chrono::steady_clock::now() - t0).count();
    res.frontier_cells = cells.size();
    size_t with_views = 0;
    for (size_t i = 0; i < clusters.size(); ++i) {
      res.clusters.push_back(clusterMsg(clusters[i], views[i]));
      with_views += views[i].empty() ? 0 : 1;
    }
    res.success = true;
    stats_->addFrontierQuery();
    res.message =
        std::to_string(cells.size()) + " frontier cells" +
        (coarse ? " (coarse cells of " + std::to_string(copy->resolution()) + " m" + grid_note + ")"
         : grid_note.empty() ? std::string()
                             : " (" + grid_note.substr(2) + ")") +
        ", viewpoint gain " + planning::viewpointGainName(q.views.gain) + "," + " in " +
        std::to_string(clusters.size()) + " clusters (" + std::to_string(with_views) +
        " with viewpoints), " + std::to_string(res.ms) + " ms";
  } catch (const std::exception& e) {
    res = fragg_map::GetFrontiers::Response();
    res.success = false;
    res.message = e.what();
    ROS_WARN_THROTTLE(1.0, "fragg_map: get_frontiers refused: %s", e.what());
  }
  return true;
}

}  // namespace fragg::ros
