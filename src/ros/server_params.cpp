// Parameters of the map server: one read of the private namespace, typed lookups by path
// ("sensor_model/hit"). The values of the core's fields are checked by the core's validate()
// only; its messages name the core's fields, renamed here to the parameters (kParameterNames).
// What is checked here belongs to the server alone (frame_id, queue, tf, markers, correction,
// collision, frontiers: the planning library's checks, named by parameter).
#include "fragg_map/ros/server_params.h"

#include <ros/console.h>

#include <algorithm>
#include <cmath>
#include <limits>
#include <set>
#include <sstream>
#include <vector>

#include "fragg_map/errors.h"
#include "fragg_map/field_names.h"
#include "fragg_map/planning/coarse_map.h"
#include "fragg_map/ros/autosave_params.h"
#include "fragg_map/ros/paging_params.h"
#include "param_lookup.h"

namespace fragg::ros {
namespace {

using XmlRpc::XmlRpcValue;

// Every name the parser asks for, present or not (parseParameters sets it): the names in the
// namespace that none asked for are the unknown ones.
thread_local std::set<std::string>* t_asked_names = nullptr;

// The value at `path` ("a/b/c") in `root`, or nullptr when absent.
const XmlRpcValue* lookup(const XmlRpcValue& root, const std::string& path) {
  if (t_asked_names) t_asked_names->insert(path);
  const XmlRpcValue* node = &root;
  std::stringstream parts(path);
  std::string part;
  while (std::getline(parts, part, '/')) {
    if (node->getType() != XmlRpcValue::TypeStruct || !node->hasMember(part)) return nullptr;
    node = &(*const_cast<XmlRpcValue*>(node))[part];
  }
  return node;
}

void readDouble(const XmlRpcValue& root, const std::string& name, double* out) {
  const XmlRpcValue* v = lookup(root, name);
  if (!v) return;
  XmlRpcValue copy = *v;
  if (copy.getType() == XmlRpcValue::TypeDouble)
    *out = static_cast<double>(copy);
  else if (copy.getType() == XmlRpcValue::TypeInt)
    *out = static_cast<int>(copy);
  else
    badParam(name, "expected a number");
  if (std::isnan(*out)) badParam(name, "is NaN");
}

void readInt(const XmlRpcValue& root, const std::string& name, int* out) {
  const XmlRpcValue* v = lookup(root, name);
  if (!v) return;
  XmlRpcValue copy = *v;
  if (copy.getType() != XmlRpcValue::TypeInt) badParam(name, "expected an integer");
  *out = static_cast<int>(copy);
}

void readBool(const XmlRpcValue& root, const std::string& name, bool* out) {
  const XmlRpcValue* v = lookup(root, name);
  if (!v) return;
  XmlRpcValue copy = *v;
  if (copy.getType() != XmlRpcValue::TypeBoolean) badParam(name, "expected true or false");
  *out = static_cast<bool>(copy);
}

void readString(const XmlRpcValue& root, const std::string& name, std::string* out) {
  const XmlRpcValue* v = lookup(root, name);
  if (!v) return;
  XmlRpcValue copy = *v;
  if (copy.getType() != XmlRpcValue::TypeString) badParam(name, "expected a string");
  *out = static_cast<std::string>(copy);
}

// A list of numbers (each an int or a double); absent keeps `out`.
void readDoubleList(const XmlRpcValue& root, const std::string& name, std::vector<double>* out) {
  const XmlRpcValue* v = lookup(root, name);
  if (!v) return;
  XmlRpcValue copy = *v;
  if (copy.getType() != XmlRpcValue::TypeArray) badParam(name, "expected a list of numbers");
  std::vector<double> values;
  for (int i = 0; i < copy.size(); ++i) {
    XmlRpcValue item = copy[i];
    if (item.getType() == XmlRpcValue::TypeDouble)
      values.push_back(static_cast<double>(item));
    else if (item.getType() == XmlRpcValue::TypeInt)
      values.push_back(static_cast<int>(item));
    else
      badParam(name, "expected a list of numbers");
    if (!std::isfinite(values.back())) badParam(name, "holds a value that is not finite");
  }
  *out = values;
}

void requireOrdered(const std::string& lo_name, double lo, const std::string& hi_name, double hi) {
  if (lo > hi)
    badParam(lo_name, std::to_string(lo) + " exceeds " + hi_name + " " + std::to_string(hi));
}

// The core's fields (as its validate() messages name them) -> the server's parameters.
const std::vector<fragg::FieldName>& parameterNames() {
  static const std::vector<fragg::FieldName> names = {
      {"resolution_m", "resolution"},
      {"occupancy.prob_hit", "sensor_model/hit"},
      {"occupancy.prob_miss", "sensor_model/miss"},
      {"occupancy.clamp_min", "sensor_model/min"},
      {"occupancy.clamp_max", "sensor_model/max"},
      {"occupancy.unknown_band", "unknown_band"},
      {"backend", "backend"},
      {"raycast", "raycast"},
      {"threads", "threads"},
      {"culling.coherence_ttl_scans", "culling/coherence_ttl_scans"},
      {"scans.point_step_m", "scan_store/point_step"},
      {"height_filter.min_z_m", "pointcloud_min_z"},
      {"height_filter.max_z_m", "pointcloud_max_z"},
      {"dynamic.void_probability", "dynamic/void_probability"},
      {"dynamic.known_radius_cells", "dynamic/known_radius"},
      {"dynamic.enabled", "dynamic/enabled"},
      {"dynamic.rule", "dynamic/rule"},
      {"dynamic.decay_log_odds_per_scan", "dynamic/decay_per_scan"},
      {"sensor.type", "sensor/type"},
      {"sensor.hfov_rad", "sensor/hfov"},
      {"sensor.vfov_rad", "sensor/vfov"},
      {"sensor.elevation_min_rad", "sensor/elevation_min"},
      {"sensor.elevation_max_rad", "sensor/elevation_max"},
      {"sensor.min_range_m", "sensor_model/min_range"},
      {"sensor.max_range_m", "sensor_model/max_range"},
      {"sensor.range_noise_m", "sensor/range_noise"},
      {"sensor.range_noise_quadratic_per_m", "sensor/range_noise_quadratic"},
      {"sensor.lidar_rings", "sensor/lidar_height"},
      {"sensor.lidar_columns", "sensor/lidar_width"},
      {"sensor.lidar_ring_elevations_rad", "sensor/lidar_ring_elevations"},
      {"sensor.lidar_azimuth_offset_rad", "sensor/lidar_azimuth_offset"},
  };
  return names;
}

// Runs core parsing or validation; its InvalidArgument comes back naming the parameters
// ("parameter 'sensor_model/hit' must be > 0.5, got 0.4").
template <typename Fn>
void asParameters(Fn&& fn) {
  try {
    fn();
  } catch (const fragg::InvalidArgument& e) {
    throw fragg::InvalidArgument("parameter " + fragg::renameFields(e.what(), parameterNames()));
  }
}

// The LiDAR's beam table for clear_no_return_rays on unorganised clouds, named as nvblox
// names it: sensor/lidar_height rings evenly spaced over sensor/elevation_min..max (sensor/type
// lidar) or sensor/lidar_ring_elevations (radians, ascending), sensor/lidar_width columns a
// revolution, sensor/lidar_azimuth_offset (radians) the azimuth of column 0.
void readLidarBeams(const XmlRpcValue& root, fragg::SensorType type, double elevation_min,
                    double elevation_max, fragg::LidarBeams& b) {
  int rings = 0, columns = 0;
  std::vector<double> elevations;
  double offset = 0.0;
  readInt(root, "sensor/lidar_height", &rings);
  readInt(root, "sensor/lidar_width", &columns);
  readDoubleList(root, "sensor/lidar_ring_elevations", &elevations);
  readDouble(root, "sensor/lidar_azimuth_offset", &offset);
  if (rings < 0) badParam("sensor/lidar_height", "must be >= 0, got " + std::to_string(rings));
  if (columns < 0) badParam("sensor/lidar_width", "must be >= 0, got " + std::to_string(columns));
  b = fragg::LidarBeams{};
  if (!elevations.empty()) {
    if (rings != 0 && size_t(rings) != elevations.size())
      badParam("sensor/lidar_height", std::to_string(rings) + " disagrees with the " +
                                          std::to_string(elevations.size()) +
                                          " sensor/lidar_ring_elevations");
    b.ring_elevations_rad = elevations;
  } else if (rings != 0) {
    if (type != fragg::SensorType::kSpinningLidar)
      badParam("sensor/lidar_height",
               "spaces its rings over sensor/elevation_min..max: needs sensor/type lidar (or "
               "give sensor/lidar_ring_elevations)");
    asParameters([&] {
      b = fragg::LidarBeams::evenlySpaced(uint32_t(rings), uint32_t(columns), elevation_min,
                                          elevation_max);
    });
  }
  b.columns = uint32_t(columns);
  b.azimuth_offset_rad = offset;
}

void readSensor(const XmlRpcValue& root, ServerParams& p) {
  std::string type = "auto", axis = "z";
  double hfov = 0.0, vfov = 0.0, min_range = 0.0, max_range = ServerParams::kDefaultMaxRangeM;
  double elevation_min = -M_PI / 2, elevation_max = M_PI / 2;
  double noise_m = 0.0, noise_quadratic = 0.0;
  readString(root, "sensor/type", &type);
  readDouble(root, "sensor/hfov", &hfov);
  readDouble(root, "sensor/vfov", &vfov);
  readString(root, "sensor/optical_axis", &axis);
  readDouble(root, "sensor/elevation_min", &elevation_min);
  readDouble(root, "sensor/elevation_max", &elevation_max);
  readDouble(root, "sensor_model/min_range", &min_range);
  readDouble(root, "sensor_model/max_range", &max_range);
  readDouble(root, "sensor/range_noise", &noise_m);
  readDouble(root, "sensor/range_noise_quadratic", &noise_quadratic);
  fragg::SensorType sensor_type{};
  asParameters([&] { sensor_type = fragg::sensorTypeFromString(type); });
  if (axis != "z" && axis != "x") badParam("sensor/optical_axis", "must be z or x");
  switch (sensor_type) {
    case fragg::SensorType::kPinhole:
      p.sensor = fragg::SensorModel::pinhole(
          hfov, vfov, min_range, max_range,
          axis == "x" ? fragg::OpticalAxis::kXForward : fragg::OpticalAxis::kZForward);
      break;
    case fragg::SensorType::kSpinningLidar:
      p.sensor =
          fragg::SensorModel::spinningLidar(elevation_min, elevation_max, min_range, max_range);
      break;
    default:
      p.sensor = fragg::SensorModel::autoFromCloud(min_range, max_range);
  }
  p.sensor.range_noise_m = noise_m;
  p.sensor.range_noise_quadratic_per_m = noise_quadratic;
  readLidarBeams(root, sensor_type, elevation_min, elevation_max, p.sensor.lidar_beams);
  asParameters([&] { p.sensor.validate(); });
}

void readScanStore(const XmlRpcValue& root, fragg::ScanStoreParams& s) {
  readBool(root, "keep_scans", &s.keep);
  double max_mb = static_cast<double>(s.max_bytes >> 20);
  readDouble(root, "scan_store/max_mb", &max_mb);
  // A conversion, not a check of the core's field (max_bytes): MiB -> bytes must fit.
  if (!(max_mb >= 0.0) || !(max_mb <= 1e9))
    badParam("scan_store/max_mb", "must be in [0, 1e9] MiB (0 = no limit)");
  s.max_bytes = static_cast<size_t>(max_mb * 1024.0 * 1024.0);
  readString(root, "scan_store/spill_dir", &s.spill_dir);
  readDouble(root, "scan_store/point_step", &s.point_step_m);
}

void readCorrection(const XmlRpcValue& root, CorrectionParams& c) {
  readDouble(root, "correction/min_translation", &c.thresholds.min_translation_m);
  if (!(c.thresholds.min_translation_m >= 0.0) || !std::isfinite(c.thresholds.min_translation_m))
    badParam("correction/min_translation", "must be a finite number of metres >= 0");
  readDouble(root, "correction/min_rotation", &c.thresholds.min_rotation_rad);
  if (!(c.thresholds.min_rotation_rad >= 0.0) || !(c.thresholds.min_rotation_rad <= M_PI))
    badParam("correction/min_rotation", "must be in [0, pi] rad");
  readDouble(root, "correction/stamp_tolerance", &c.stamp_tolerance_s);
  if (!(c.stamp_tolerance_s >= 0.0) || !(c.stamp_tolerance_s <= 3600.0))
    badParam("correction/stamp_tolerance", "must be in [0, 3600] s");
  readString(root, "correction/path_child_frame", &c.path_child_frame);
  if (!c.path_child_frame.empty() && c.path_child_frame[0] == '/')
    c.path_child_frame.erase(0, 1);  // tf2 frames have no leading slash
  readBool(root, "correction/subscribe_path", &c.subscribe_path);
}

void readCollision(const XmlRpcValue& root, CollisionParams& c) {
  readBool(root, "collision/unknown_is_occupied", &c.unknown_is_occupied);
  readDouble(root, "collision/margin", &c.margin_m);
  if (!(c.margin_m >= 0.0) || !std::isfinite(c.margin_m))
    badParam("collision/margin", "must be a finite number of metres >= 0");
  readString(root, "collision/mesh", &c.mesh);
  if (!c.mesh.empty() && c.mesh[0] != '/')
    badParam("collision/mesh", "must be an absolute path (got '" + c.mesh + "')");
  readDouble(root, "collision/mesh_scale", &c.mesh_scale);
  if (!(c.mesh_scale > 0.0) || !std::isfinite(c.mesh_scale))
    badParam("collision/mesh_scale", "must be finite and > 0");
  readInt(root, "collision/max_markers", &c.max_markers);
  if (c.max_markers < 0) badParam("collision/max_markers", "must be >= 0");
}

// The planning library's checks, their messages prefixed with the parameter group.
template <typename Fn>
void asFrontierParameters(const std::string& group, Fn&& fn) {
  try {
    fn();
  } catch (const fragg::InvalidArgument& e) {
    badParam(group, e.what());
  }
}

void readFrontierSensor(const XmlRpcValue& root, planning::GainSensor& s) {
  std::string type = "pinhole";
  readString(root, "frontiers/sensor/type", &type);
  if (type == "lidar") {
    s.kind = planning::GainSensor::Kind::kLidar;
    s.columns = 360;  // as `fragg_map frontiers --sensor lidar`
    s.rows = 16;
  } else if (type != "pinhole") {
    badParam("frontiers/sensor/type", "must be pinhole or lidar, got '" + type + "'");
  }
  readInt(root, "frontiers/sensor/columns", &s.columns);
  readInt(root, "frontiers/sensor/rows", &s.rows);
  readDouble(root, "frontiers/sensor/hfov", &s.horizontal_fov_rad);
  readDouble(root, "frontiers/sensor/vfov", &s.vertical_fov_rad);
  readDouble(root, "frontiers/sensor/elevation_min", &s.min_elevation_rad);
  readDouble(root, "frontiers/sensor/elevation_max", &s.max_elevation_rad);
  readDouble(root, "frontiers/sensor/max_range", &s.max_range_m);
  asFrontierParameters("frontiers/sensor", [&] { s.validate(); });
}

void readFrontiers(const XmlRpcValue& root, FrontierParams& f) {
  readDouble(root, "frontiers/rate_hz", &f.rate_hz);
  if (!(f.rate_hz > 0.0) || !std::isfinite(f.rate_hz))
    badParam("frontiers/rate_hz", "must be a finite rate in Hz > 0");
  std::vector<double> box_min, box_max;
  readDoubleList(root, "frontiers/box_min", &box_min);
  readDoubleList(root, "frontiers/box_max", &box_max);
  if (!box_min.empty() || !box_max.empty()) {
    if (box_min.size() != 3 || box_max.size() != 3)
      badParam("frontiers/box_min", "box_min and box_max take [x, y, z] each, both or neither");
    f.filter.use_box = true;
    f.filter.box_min_m = Eigen::Vector3d(box_min[0], box_min[1], box_min[2]);
    f.filter.box_max_m = Eigen::Vector3d(box_max[0], box_max[1], box_max[2]);
  }
  double min_z = -std::numeric_limits<double>::infinity();
  double max_z = std::numeric_limits<double>::infinity();
  readDouble(root, "frontiers/min_z", &min_z);
  readDouble(root, "frontiers/max_z", &max_z);
  if (std::isfinite(min_z) || std::isfinite(max_z)) {
    constexpr double kOpen = 1e9;  // an open side of the band
    f.filter.use_height = true;
    f.filter.min_z_m = std::isfinite(min_z) ? min_z : -kOpen;
    f.filter.max_z_m = std::isfinite(max_z) ? max_z : kOpen;
  }
  readDouble(root, "frontiers/min_obstacle_distance", &f.filter.min_obstacle_distance_m);
  // The library's checks, one part at a time so that the message names the parameter.
  const auto check_filter_part = [&](const std::string& name, auto&& set_part) {
    planning::FrontierFilter part;
    set_part(part);
    asFrontierParameters(name, [&] { part.validate(); });
  };
  check_filter_part("frontiers/box_min", [&](planning::FrontierFilter& p) {
    p.use_box = f.filter.use_box, p.box_min_m = f.filter.box_min_m;
    p.box_max_m = f.filter.box_max_m;
  });
  check_filter_part("frontiers/min_z", [&](planning::FrontierFilter& p) {
    p.use_height = f.filter.use_height, p.min_z_m = f.filter.min_z_m;
    p.max_z_m = f.filter.max_z_m;
  });
  check_filter_part("frontiers/min_obstacle_distance", [&](planning::FrontierFilter& p) {
    p.min_obstacle_distance_m = f.filter.min_obstacle_distance_m;
  });
  int min_cluster = static_cast<int>(f.clusters.min_cells);
  readInt(root, "frontiers/min_cluster", &min_cluster);
  if (min_cluster < 1) badParam("frontiers/min_cluster", "must be >= 1");
  f.clusters.min_cells = static_cast<uint64_t>(min_cluster);
  readDouble(root, "frontiers/max_extent", &f.clusters.max_extent_m);
  asFrontierParameters("frontiers/max_extent", [&] { f.clusters.validate(); });
  readInt(root, "frontiers/viewpoints", &f.viewpoints);
  if (f.viewpoints < 0) badParam("frontiers/viewpoints", "must be >= 0 (0: no viewpoints)");
  const auto check_view_part = [&](const std::string& name, auto&& set_part) {
    planning::ViewpointOptions part;
    set_part(part);
    asFrontierParameters(name, [&] { part.validate(); });
  };
  readDoubleList(root, "frontiers/radii", &f.views.radii_m);
  check_view_part("frontiers/radii", [&](auto& p) { p.radii_m = f.views.radii_m; });
  readDoubleList(root, "frontiers/heights", &f.views.heights_m);
  check_view_part("frontiers/heights", [&](auto& p) { p.heights_m = f.views.heights_m; });
  readInt(root, "frontiers/angles", &f.views.angles);
  check_view_part("frontiers/angles", [&](auto& p) { p.angles = f.views.angles; });
  readDouble(root, "frontiers/clearance", &f.views.clearance_m);
  check_view_part("frontiers/clearance", [&](auto& p) { p.clearance_m = f.views.clearance_m; });
  readFrontierSensor(root, f.views.sensor);
  f.views.top_k = std::max(f.viewpoints, 1);
  f.views.validate();
  readInt(root, "frontiers/max_marker_cells", &f.max_marker_cells);
  if (f.max_marker_cells < 0) badParam("frontiers/max_marker_cells", "must be >= 0");
  readInt(root, "frontiers/coarse_cells", &f.coarse_cells);
  if (f.coarse_cells != 0 && !planning::validCoarseCells(f.coarse_cells))
    badParam("frontiers/coarse_cells",
             "must be 1, 2, 4 or 8 map cells (0: from the LiDAR's beam spacing)");
  std::string gain = "auto";
  readString(root, "frontiers/gain", &gain);
  if (gain != "auto")
    asFrontierParameters("frontiers/gain", [&] { f.gain = planning::viewpointGainFromName(gain); });
  if (f.gain) f.views.gain = *f.gain;  // the topics' gain too (auto: entropy on the map's cells)
  readDouble(root, "frontiers/deadline_s", &f.deadline_s);
  if (!std::isfinite(f.deadline_s) || f.deadline_s < 0.0)
    badParam("frontiers/deadline_s", "must be a finite time in s >= 0 (0: none)");
}

void readOctomapCompat(const XmlRpcValue& root, OctomapCompatParams& o) {
  readString(root, "base_frame_id", &o.base_frame_id);
  if (!o.base_frame_id.empty() && o.base_frame_id[0] == '/') o.base_frame_id.erase(0, 1);
  if (o.base_frame_id.empty()) badParam("base_frame_id", "must not be empty");
  readBool(root, "filter_ground", &o.filter_ground);
  readDouble(root, "ground_filter/distance", &o.ground_distance_m);
  readDouble(root, "ground_filter/angle", &o.ground_angle_rad);
  readDouble(root, "ground_filter/plane_distance", &o.ground_plane_distance_m);
  if (!(o.ground_distance_m > 0.0) || !std::isfinite(o.ground_distance_m))
    badParam("ground_filter/distance", "must be a finite distance in metres > 0");
  if (!(o.ground_angle_rad >= 0.0) || !(o.ground_angle_rad <= M_PI / 2))
    badParam("ground_filter/angle", "must be in [0, pi/2] rad");
  if (!(o.ground_plane_distance_m >= 0.0) || !std::isfinite(o.ground_plane_distance_m))
    badParam("ground_filter/plane_distance", "must be a finite distance in metres >= 0");
  readBool(root, "filter_speckles", &o.filter_speckles);
  readBool(root, "height_map", &o.height_map);
  readBool(root, "colored_map", &o.colored_map);
  const char* channels[4] = {"color/r", "color/g", "color/b", "color/a"};
  for (int i = 0; i < 4; ++i) {
    double v = o.color_rgba[i];
    readDouble(root, channels[i], &v);
    if (!(v >= 0.0) || !(v <= 1.0)) badParam(channels[i], "must be in [0, 1]");
    o.color_rgba[i] = static_cast<float>(v);
  }
  readBool(root, "incremental_2D_projection", &o.incremental_2D_projection);
  readBool(root, "compress_map", &o.compress_map);
  readBool(root, "clear_bbx_free", &o.clear_bbx_free);
  readBool(root, "projected_map/octomap_bounds", &o.projected_map_octomap_bounds);
  readString(root, "map_file", &o.map_file);
}

// Levenshtein distance (names are short).
size_t editDistance(const std::string& a, const std::string& b) {
  std::vector<size_t> row(b.size() + 1);
  for (size_t j = 0; j <= b.size(); ++j) row[j] = j;
  for (size_t i = 1; i <= a.size(); ++i) {
    size_t diagonal = row[0];
    row[0] = i;
    for (size_t j = 1; j <= b.size(); ++j) {
      const size_t above = row[j];
      row[j] = std::min({row[j] + 1, row[j - 1] + 1, diagonal + (a[i - 1] == b[j - 1] ? 0 : 1)});
      diagonal = above;
    }
  }
  return row[b.size()];
}

// The leaves of `node` ("a/b/c") that no parameter asked for, with the nearest asked name as a
// hint when it is close (at most 2 edits).
void collectUnknown(const XmlRpcValue& node, const std::string& path,
                    const std::set<std::string>& asked, std::vector<std::string>* unknown) {
  if (node.getType() == XmlRpcValue::TypeStruct && !asked.count(path)) {
    XmlRpcValue copy = node;
    for (auto it = copy.begin(); it != copy.end(); ++it)
      collectUnknown(it->second, path.empty() ? it->first : path + "/" + it->first, asked, unknown);
    return;
  }
  if (path.empty() || asked.count(path)) return;
  std::string hint;
  size_t best = 3;
  for (const std::string& name : asked) {
    const size_t d = editDistance(path, name);
    if (d < best) best = d, hint = name;
  }
  unknown->push_back(hint.empty() ? path : path + " (did you mean " + hint + "?)");
}

ServerParams parseKnown(const XmlRpcValue& root);

}  // namespace

ServerParams parseParameters(const XmlRpcValue& root) {
  std::set<std::string> asked;
  t_asked_names = &asked;
  ServerParams p;
  try {
    p = parseKnown(root);
  } catch (...) {
    t_asked_names = nullptr;
    throw;
  }
  t_asked_names = nullptr;
  // paging/* are read by paging_params.cpp, autosave/* and file_root by autosave_params.cpp (the
  // map server reads all three).
  for (const std::string& name : pagingParameterNames()) asked.insert(name);
  for (const std::string& name : autosaveParameterNames()) asked.insert(name);
  if (root.valid() && root.getType() == XmlRpcValue::TypeStruct)
    collectUnknown(root, "", asked, &p.unknown_parameters);
  return p;
}

namespace {

ServerParams parseKnown(const XmlRpcValue& root) {
  if (root.valid() && root.getType() != XmlRpcValue::TypeStruct)
    badParam("~", "the private namespace is not a struct");
  ServerParams p;
  fragg::MapParams& m = p.map;
  readDouble(root, "resolution", &m.resolution_m);
  readString(root, "frame_id", &p.frame_id);
  if (p.frame_id.empty()) badParam("frame_id", "must not be empty");
  readString(root, "file_root", &p.file_root);
  readString(root, "trace_csv", &p.trace_csv);

  readDouble(root, "sensor_model/hit", &m.occupancy.prob_hit);
  readDouble(root, "sensor_model/miss", &m.occupancy.prob_miss);
  readDouble(root, "sensor_model/min", &m.occupancy.clamp_min);
  readDouble(root, "sensor_model/max", &m.occupancy.clamp_max);
  readDouble(root, "unknown_band", &m.occupancy.unknown_band);

  std::string backend = "auto", raycast = "dda";
  readString(root, "backend", &backend);
  readString(root, "raycast", &raycast);
  asParameters([&] {
    m.backend = fragg::backendFromString(backend);
    m.raycast = fragg::rayCastFromString(raycast);
  });
  readBool(root, "clear_no_return_rays", &m.clear_no_return_rays);
  readBool(root, "sensor_model/free_cut_cell", &m.free_cut_cell);
  readInt(root, "threads", &m.threads);
  readBool(root, "culling/plane_memory", &m.culling.plane_memory);
  readBool(root, "culling/rotation_coherence", &m.culling.rotation_coherence);
  readBool(root, "culling/translation_coherence", &m.culling.translation_coherence);
  readInt(root, "culling/coherence_ttl_scans", &m.culling.coherence_ttl_scans);
  readScanStore(root, m.scans);
  readDouble(root, "pointcloud_min_z", &m.height_filter.min_z_m);
  readDouble(root, "pointcloud_max_z", &m.height_filter.max_z_m);
  readBool(root, "dynamic/enabled", &m.dynamic.enabled);
  readDouble(root, "dynamic/void_probability", &m.dynamic.void_probability);
  readInt(root, "dynamic/known_radius", &m.dynamic.known_radius_cells);
  readDouble(root, "dynamic/decay_per_scan", &m.dynamic.decay_log_odds_per_scan);
  std::string void_rule = fragg::toString(m.dynamic.rule);
  readString(root, "dynamic/rule", &void_rule);
  asParameters([&] { m.dynamic.rule = fragg::voidSpaceRuleFromString(void_rule); });
  asParameters([&] { m.validate(); });

  readSensor(root, p);
  // The points an unorganised cloud loses to the height band would read as beams with no
  // return (Map::insert refuses every such cloud): refused once, at start-up.
  if (m.clear_no_return_rays && !p.sensor.lidar_beams.empty() && m.height_filter.active())
    badParam("sensor/lidar_height",
             "(a beam table with clear_no_return_rays) cannot be combined with "
             "pointcloud_min_z / pointcloud_max_z: points cut by the band would read as no "
             "returns");

  readDouble(root, "occupancy_min_z", &p.occupancy_min_z_m);
  readDouble(root, "occupancy_max_z", &p.occupancy_max_z_m);
  requireOrdered("occupancy_min_z", p.occupancy_min_z_m, "occupancy_max_z", p.occupancy_max_z_m);
  readBool(root, "latch", &p.latch);
  readBool(root, "publish_free_space", &p.publish_free_space);
  readInt(root, "queue_size", &p.queue_size);
  if (p.queue_size < 1) badParam("queue_size", "must be >= 1");
  readDouble(root, "tf_tolerance", &p.tf_tolerance_s);
  if (!(p.tf_tolerance_s >= 0.0) || !std::isfinite(p.tf_tolerance_s))
    badParam("tf_tolerance", "must be a finite number of seconds >= 0");
  readDouble(root, "marker_rate", &p.marker_rate_hz);
  if (!(p.marker_rate_hz >= 0.0) || !std::isfinite(p.marker_rate_hz))
    badParam("marker_rate", "must be a finite rate in Hz >= 0 (0 = after every cloud)");
  readDouble(root, "map_rate", &p.map_rate_hz);
  if (!(p.map_rate_hz >= 0.0) || !std::isfinite(p.map_rate_hz))
    badParam("map_rate", "must be a finite rate in Hz >= 0 (0 = after every cloud)");
  readBool(root, "paced_outputs", &p.paced_outputs);
  readBool(root, "mirror_every_cloud", &p.mirror_every_cloud);
  readBool(root, "shares_between_clouds", &p.shares_between_clouds);
  readInt(root, "markers/chunk_blocks", &p.marker_chunk_blocks);
  if (p.marker_chunk_blocks < 1 || p.marker_chunk_blocks > 64)
    badParam("markers/chunk_blocks", "must be 1..64 blocks a side");
  readDouble(root, "markers/color_min_z", &p.color_min_z_m);
  readDouble(root, "markers/color_max_z", &p.color_max_z_m);
  if (!std::isfinite(p.color_min_z_m) || !std::isfinite(p.color_max_z_m) ||
      !(p.color_min_z_m < p.color_max_z_m))
    badParam("markers/color_min_z", "must be finite and below markers/color_max_z");
  readCorrection(root, p.correction);
  readCollision(root, p.collision);
  readFrontiers(root, p.frontiers);
  readOctomapCompat(root, p.octomap);
  return p;
}

}  // namespace

ServerParams readParameters(const ::ros::NodeHandle& private_nh) {
  XmlRpcValue root;  // stays invalid (every default) when the namespace holds nothing
  private_nh.getParam(private_nh.getNamespace(), root);
  ServerParams p = parseParameters(root);
  if (!p.unknown_parameters.empty()) {
    std::string names;
    for (const std::string& name : p.unknown_parameters)
      names += (names.empty() ? "" : ", ") + name;
    ROS_WARN("fragg_map: %zu parameter(s) under %s that fragg_map does not read (ignored): %s",
             p.unknown_parameters.size(), private_nh.getNamespace().c_str(), names.c_str());
  }
  return p;
}

}  // namespace fragg::ros
