// parseParameters: defaults, octomap_server names, and one failure per invalid value, naming
// the parameter.
#include "fragg_map/ros/server_params.h"

#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <limits>
#include <string>
#include <utility>
#include <vector>

#include "fragg_map/errors.h"

namespace {

using XmlRpc::XmlRpcValue;

// Sets root["a"]["b"] = value for path "a/b".
void set(XmlRpcValue& root, const std::string& path, const XmlRpcValue& value) {
  XmlRpcValue* node = &root;
  size_t start = 0;
  for (size_t slash; (slash = path.find('/', start)) != std::string::npos; start = slash + 1)
    node = &(*node)[path.substr(start, slash - start)];
  (*node)[path.substr(start)] = value;
}

void expectRejected(const std::string& name, const XmlRpcValue& value) {
  XmlRpcValue root;
  set(root, name, value);
  try {
    fragg::ros::parseParameters(root);
    FAIL() << name << " = " << const_cast<XmlRpcValue&>(value).toXml() << " was accepted";
  } catch (const fragg::InvalidArgument& e) {
    const std::string what = e.what();
    EXPECT_NE(what.find("'" + name + "'"), std::string::npos)
        << "the error does not name " << name << ": " << what;
    // The core's field names are renamed to parameters, never shown as they are.
    for (const char* core :
         {"occupancy.", "sensor.", "height_filter.", "resolution_m", "scans.", "culling."})
      EXPECT_EQ(what.find(core), std::string::npos) << "core name " << core << " in: " << what;
  }
}

std::string rejection(const XmlRpcValue& root) {
  try {
    fragg::ros::parseParameters(root);
  } catch (const fragg::InvalidArgument& e) {
    return e.what();
  }
  return "(accepted)";
}

TEST(ServerParams, EmptyNamespaceGivesTheCoreDefaults) {
  const fragg::ros::ServerParams p = fragg::ros::parseParameters(XmlRpcValue());
  const fragg::MapParams core;
  EXPECT_EQ(p.map.resolution_m, core.resolution_m);
  EXPECT_EQ(p.map.occupancy.prob_hit, core.occupancy.prob_hit);
  EXPECT_EQ(p.map.occupancy.clamp_max, core.occupancy.clamp_max);
  EXPECT_EQ(p.map.backend, core.backend);
  EXPECT_EQ(p.frame_id, "map");
  EXPECT_EQ(p.sensor.type, fragg::SensorType::kAuto);
  // The server's own default (the core's is -1, no limit): far outliers cannot stretch the map.
  EXPECT_EQ(p.sensor.max_range_m, fragg::ros::ServerParams::kDefaultMaxRangeM);
  EXPECT_GT(p.sensor.max_range_m, 0.0);
  EXPECT_EQ(p.queue_size, 5);
  EXPECT_TRUE(p.latch);  // octomap_server's default
  // Whole-map outputs and markers after every cloud (octomap_server's behaviour).
  EXPECT_EQ(p.map_rate_hz, 0.0);
  EXPECT_EQ(p.marker_rate_hz, 0.0);
  EXPECT_TRUE(std::isinf(p.map.height_filter.min_z_m));
  EXPECT_TRUE(p.unknown_parameters.empty());
}

TEST(ServerParams, UnknownAndMisspelledNamesAreListedWithAHint) {
  XmlRpcValue root;
  set(root, "sensor_model/hitt", 0.7);  // one edit from sensor_model/hit
  set(root, "sensor_model/hit", 0.7);
  set(root, "resolutoin", 0.1);  // two edits from resolution
  set(root, "totally_unrelated", true);
  set(root, "frame_id", "map");
  const fragg::ros::ServerParams p = fragg::ros::parseParameters(root);
  ASSERT_EQ(p.unknown_parameters.size(), 3u);
  std::vector<std::string> sorted = p.unknown_parameters;
  std::sort(sorted.begin(), sorted.end());
  EXPECT_EQ(sorted[0], "resolutoin (did you mean resolution?)");
  EXPECT_EQ(sorted[1], "sensor_model/hitt (did you mean sensor_model/hit?)");
  EXPECT_EQ(sorted[2], "totally_unrelated");
  // The misspelled value is not taken for the right name.
  EXPECT_EQ(p.map.resolution_m, fragg::MapParams().resolution_m);
}

TEST(ServerParams, OctomapServerNamesAreRead) {
  XmlRpcValue root;
  set(root, "base_frame_id", "/base_link");
  set(root, "filter_ground", true);
  set(root, "ground_filter/distance", 0.05);
  set(root, "ground_filter/angle", 0.2);
  set(root, "ground_filter/plane_distance", 0.1);
  set(root, "filter_speckles", true);
  set(root, "height_map", false);
  set(root, "colored_map", false);
  set(root, "color/r", 1.0);
  set(root, "color/g", 0.5);
  set(root, "color/b", 0);
  set(root, "color/a", 0.8);
  set(root, "incremental_2D_projection", true);
  set(root, "compress_map", false);
  set(root, "map_file", "/tmp/x.bt");
  const fragg::ros::ServerParams p = fragg::ros::parseParameters(root);
  EXPECT_TRUE(p.unknown_parameters.empty());
  const fragg::ros::OctomapCompatParams& o = p.octomap;
  EXPECT_EQ(o.base_frame_id, "base_link");
  EXPECT_TRUE(o.filter_ground);
  EXPECT_EQ(o.ground_distance_m, 0.05);
  EXPECT_EQ(o.ground_angle_rad, 0.2);
  EXPECT_EQ(o.ground_plane_distance_m, 0.1);
  EXPECT_TRUE(o.filter_speckles);
  EXPECT_FALSE(o.height_map);
  EXPECT_FLOAT_EQ(o.color_rgba[0], 1.0f);
  EXPECT_FLOAT_EQ(o.color_rgba[1], 0.5f);
  EXPECT_FLOAT_EQ(o.color_rgba[2], 0.0f);
  EXPECT_FLOAT_EQ(o.color_rgba[3], 0.8f);
  EXPECT_TRUE(o.incremental_2D_projection);
  EXPECT_FALSE(o.compress_map);
  EXPECT_EQ(o.map_file, "/tmp/x.bt");
  expectRejected("color/r", 1.5);
  expectRejected("ground_filter/distance", 0.0);
  expectRejected("ground_filter/angle", -0.1);
  expectRejected("base_frame_id", "");
  expectRejected("height_map", 1);
}

TEST(ServerParams, ScanStoreAndCorrectionDefaults) {
  const fragg::ros::ServerParams p = fragg::ros::parseParameters(XmlRpcValue());
  EXPECT_TRUE(p.map.scans.keep);  // the server keeps scans, the core does not by default
  EXPECT_EQ(p.map.scans.max_bytes, size_t{2048} << 20);
  // Float32 kept points: the kept scans do not change the map (octomap_server's map).
  EXPECT_EQ(p.map.scans.point_step_m, 0.0);
  EXPECT_EQ(p.map.scans.spill_dir, "");
  EXPECT_EQ(p.correction.thresholds.min_translation_m, 0.05);
  EXPECT_EQ(p.correction.thresholds.min_rotation_rad, 0.01);
  EXPECT_EQ(p.correction.stamp_tolerance_s, 0.001);
  EXPECT_EQ(p.correction.path_child_frame, "");
  EXPECT_TRUE(p.correction.subscribe_path);
}

TEST(ServerParams, ReadsScanStoreAndCorrection) {
  XmlRpcValue root;
  set(root, "keep_scans", false);
  set(root, "scan_store/max_mb", 0);  // no limit
  set(root, "scan_store/spill_dir", std::string("/tmp/spill"));
  set(root, "scan_store/point_step", 0.002);
  set(root, "correction/min_translation", 0.1);
  set(root, "correction/min_rotation", 0.02);
  set(root, "correction/stamp_tolerance", 0.01);
  set(root, "correction/path_child_frame", std::string("/base_link"));
  set(root, "correction/subscribe_path", false);
  const fragg::ros::ServerParams p = fragg::ros::parseParameters(root);
  EXPECT_FALSE(p.map.scans.keep);
  EXPECT_EQ(p.map.scans.max_bytes, 0u);
  EXPECT_EQ(p.map.scans.spill_dir, "/tmp/spill");
  EXPECT_EQ(p.map.scans.point_step_m, 0.002);
  EXPECT_EQ(p.correction.thresholds.min_translation_m, 0.1);
  EXPECT_EQ(p.correction.thresholds.min_rotation_rad, 0.02);
  EXPECT_EQ(p.correction.stamp_tolerance_s, 0.01);
  EXPECT_EQ(p.correction.path_child_frame, "base_link");  // tf2 frames have no leading slash
  EXPECT_FALSE(p.correction.subscribe_path);
  XmlRpcValue mb;
  set(mb, "scan_store/max_mb", 1.5);
  EXPECT_EQ(fragg::ros::parseParameters(mb).map.scans.max_bytes, size_t{3} << 19);
}

TEST(ServerParams, InvalidScanStoreAndCorrectionValuesNameTheParameter) {
  expectRejected("keep_scans", 1);
  expectRejected("scan_store/max_mb", -1.0);
  expectRejected("scan_store/max_mb", std::string("big"));
  expectRejected("scan_store/spill_dir", 3);
  expectRejected("scan_store/point_step", -0.001);
  expectRejected("scan_store/point_step", 0.5);
  expectRejected("correction/min_translation", -0.01);
  expectRejected("correction/min_translation", std::numeric_limits<double>::infinity());
  expectRejected("correction/min_rotation", -0.01);
  expectRejected("correction/min_rotation", 4.0);
  expectRejected("correction/stamp_tolerance", -1e-3);
  expectRejected("correction/path_child_frame", 7);
  expectRejected("correction/subscribe_path", std::string("yes"));
}

TEST(ServerParams, CollisionDefaultsValuesAndRefusals) {
  const fragg::ros::ServerParams d = fragg::ros::parseParameters(XmlRpcValue());
  EXPECT_FALSE(d.collision.unknown_is_occupied);
  EXPECT_EQ(d.collision.margin_m, 0.0);
  EXPECT_EQ(d.collision.mesh, "");
  EXPECT_EQ(d.collision.mesh_scale, 1.0);
  EXPECT_EQ(d.collision.max_markers, 500);
  XmlRpcValue root;
  set(root, "collision/unknown_is_occupied", true);
  set(root, "collision/margin", 0.1);
  set(root, "collision/mesh", std::string("/robots/base.obj"));
  set(root, "collision/mesh_scale", 0.001);
  set(root, "collision/max_markers", 20);
  const fragg::ros::ServerParams p = fragg::ros::parseParameters(root);
  EXPECT_TRUE(p.collision.unknown_is_occupied);
  EXPECT_EQ(p.collision.margin_m, 0.1);
  EXPECT_EQ(p.collision.mesh, "/robots/base.obj");
  EXPECT_EQ(p.collision.mesh_scale, 0.001);
  EXPECT_EQ(p.collision.max_markers, 20);
  expectRejected("collision/unknown_is_occupied", 1);
  expectRejected("collision/margin", -0.01);
  expectRejected("collision/margin", std::numeric_limits<double>::infinity());
  expectRejected("collision/mesh", std::string("robot.obj"));  // relative
  expectRejected("collision/mesh_scale", 0.0);
  expectRejected("collision/mesh_scale", -2.0);
  expectRejected("collision/max_markers", -1);
}

TEST(ServerParams, ReadsEveryName) {
  XmlRpcValue root;
  set(root, "resolution", 0.1);
  set(root, "frame_id", std::string("odom"));
  set(root, "sensor_model/hit", 0.8);
  set(root, "sensor_model/miss", 0.3);
  set(root, "sensor_model/min", 0.1);
  set(root, "sensor_model/max", 0.95);
  set(root, "sensor_model/max_range", 30);  // an int where a double is expected
  set(root, "sensor_model/min_range", 0.5);
  set(root, "pointcloud_min_z", -2.0);
  set(root, "pointcloud_max_z", 5.0);
  set(root, "occupancy_min_z", 0.1);
  set(root, "occupancy_max_z", 1.8);
  set(root, "latch", false);
  set(root, "mirror_every_cloud", true);
  set(root, "shares_between_clouds", false);
  set(root, "publish_free_space", true);
  set(root, "backend", std::string("cpu"));
  set(root, "raycast", std::string("bresenham"));
  set(root, "sensor/type", std::string("pinhole"));
  set(root, "sensor/hfov", 1.2);
  set(root, "sensor/vfov", 0.9);
  set(root, "queue_size", 3);
  set(root, "tf_tolerance", 0.25);
  set(root, "marker_rate", 2);  // an int where a double is expected
  set(root, "map_rate", 0.5);
  const fragg::ros::ServerParams p = fragg::ros::parseParameters(root);
  EXPECT_EQ(p.map.resolution_m, 0.1);
  EXPECT_EQ(p.frame_id, "odom");
  EXPECT_TRUE(p.mirror_every_cloud);
  EXPECT_FALSE(p.shares_between_clouds);
  EXPECT_EQ(p.map.occupancy.prob_hit, 0.8);
  EXPECT_EQ(p.map.occupancy.prob_miss, 0.3);
  EXPECT_EQ(p.map.occupancy.clamp_min, 0.1);
  EXPECT_EQ(p.map.occupancy.clamp_max, 0.95);
  EXPECT_EQ(p.sensor.max_range_m, 30.0);
  EXPECT_EQ(p.sensor.min_range_m, 0.5);
  EXPECT_EQ(p.map.height_filter.min_z_m, -2.0);
  EXPECT_EQ(p.map.height_filter.max_z_m, 5.0);
  EXPECT_EQ(p.occupancy_min_z_m, 0.1);
  EXPECT_EQ(p.occupancy_max_z_m, 1.8);
  EXPECT_FALSE(p.latch);
  EXPECT_TRUE(p.publish_free_space);
  EXPECT_EQ(p.map.backend, fragg::Backend::kCpu);
  EXPECT_EQ(p.map.raycast, fragg::RayCast::kBresenham);
  EXPECT_EQ(p.sensor.type, fragg::SensorType::kPinhole);
  EXPECT_EQ(p.sensor.hfov_rad, 1.2);
  EXPECT_EQ(p.sensor.vfov_rad, 0.9);
  EXPECT_EQ(p.queue_size, 3);
  EXPECT_EQ(p.tf_tolerance_s, 0.25);
  EXPECT_EQ(p.marker_rate_hz, 2.0);
  EXPECT_EQ(p.map_rate_hz, 0.5);
}

TEST(ServerParams, DynamicRuleIsReadAndBadNamesRefused) {
  XmlRpcValue root;
  set(root, "keep_scans", false);  // the node keeps scans by default; dynamic mapping cannot
  set(root, "dynamic/enabled", true);
  set(root, "dynamic/rule", std::string("surround"));
  set(root, "dynamic/known_radius", 1);
  const fragg::ros::ServerParams p = fragg::ros::parseParameters(root);
  EXPECT_TRUE(p.map.dynamic.enabled);
  EXPECT_EQ(p.map.dynamic.rule, fragg::VoidSpaceRule::kSurround);
  EXPECT_EQ(p.map.dynamic.known_radius_cells, 1);
  EXPECT_TRUE(p.unknown_parameters.empty());
  XmlRpcValue bad;
  set(bad, "dynamic/rule", std::string("dufomap"));
  EXPECT_EQ(rejection(bad),
            "parameter 'dynamic/rule' must be pass-through or surround, got 'dufomap'");
  expectRejected("dynamic/rule", 1);
  // Forgetting: read as a rate, refused out of [0, 4] naming the parameter.
  XmlRpcValue decay;
  set(decay, "keep_scans", false);
  set(decay, "dynamic/decay_per_scan", 0.5);
  EXPECT_EQ(fragg::ros::parseParameters(decay).map.dynamic.decay_log_odds_per_scan, 0.5);
  XmlRpcValue negative;
  set(negative, "keep_scans", false);
  set(negative, "dynamic/decay_per_scan", -1.0);
  EXPECT_NE(rejection(negative).find("dynamic/decay_per_scan"), std::string::npos)
      << rejection(negative);
}

TEST(ServerParams, LidarSensor) {
  XmlRpcValue root;
  set(root, "sensor/type", std::string("lidar"));
  set(root, "sensor/elevation_min", -0.3);
  set(root, "sensor/elevation_max", 0.3);
  set(root, "sensor/range_noise", 0.02);
  set(root, "sensor/range_noise_quadratic", 0.001);
  const fragg::ros::ServerParams p = fragg::ros::parseParameters(root);
  EXPECT_EQ(p.sensor.type, fragg::SensorType::kSpinningLidar);
  EXPECT_EQ(p.sensor.range_noise_m, 0.02);
  EXPECT_EQ(p.sensor.range_noise_quadratic_per_m, 0.001);
  EXPECT_EQ(p.sensor.elevation_min_rad, -0.3);
  EXPECT_EQ(p.sensor.elevation_max_rad, 0.3);
  EXPECT_TRUE(p.sensor.lidar_beams.empty());
}

// The beam table of clear_no_return_rays on unorganised clouds, nvblox's names.
TEST(ServerParams, LidarBeamTable) {
  XmlRpcValue root;
  set(root, "sensor/type", std::string("lidar"));
  set(root, "sensor/elevation_min", -0.3);
  set(root, "sensor/elevation_max", 0.3);
  set(root, "sensor/lidar_height", 16);
  set(root, "sensor/lidar_width", 1800);
  const fragg::ros::ServerParams p = fragg::ros::parseParameters(root);
  ASSERT_EQ(p.sensor.lidar_beams.rings(), 16u);
  EXPECT_EQ(p.sensor.lidar_beams.columns, 1800u);
  EXPECT_DOUBLE_EQ(p.sensor.lidar_beams.ring_elevations_rad.front(), -0.3);
  EXPECT_DOUBLE_EQ(p.sensor.lidar_beams.ring_elevations_rad.back(), 0.3);
  EXPECT_TRUE(p.unknown_parameters.empty());

  XmlRpcValue no_columns = root;
  set(no_columns, "sensor/lidar_width", 0);
  EXPECT_NE(rejection(no_columns).find("sensor/lidar_width"), std::string::npos)
      << rejection(no_columns);
  XmlRpcValue unordered = root;
  XmlRpcValue list;
  list.setSize(2);
  list[0] = 0.1;
  list[1] = -0.1;
  unordered["sensor"]["lidar_ring_elevations"] = list;
  set(unordered, "sensor/lidar_height", 0);
  EXPECT_NE(rejection(unordered).find("sensor/lidar_ring_elevations"), std::string::npos)
      << rejection(unordered);
  XmlRpcValue banded = root;
  set(banded, "clear_no_return_rays", true);
  set(banded, "pointcloud_min_z", 0.2);
  EXPECT_NE(rejection(banded).find("pointcloud_min_z"), std::string::npos) << rejection(banded);
  set(banded, "clear_no_return_rays", false);
  EXPECT_EQ(fragg::ros::parseParameters(banded).sensor.lidar_beams.rings(), 16u);
  XmlRpcValue auto_even;
  set(auto_even, "sensor/lidar_height", 16);
  set(auto_even, "sensor/lidar_width", 1800);
  EXPECT_NE(rejection(auto_even).find("sensor/lidar_height"), std::string::npos)
      << rejection(auto_even);
}

TEST(ServerParams, InvalidValuesNameTheParameter) {
  expectRejected("resolution", 0.0);
  expectRejected("resolution", -0.05);
  expectRejected("resolution", std::string("fine"));
  expectRejected("resolution", std::nan(""));
  expectRejected("frame_id", std::string(""));
  expectRejected("sensor_model/hit", 0.4);
  expectRejected("sensor_model/hit", 1.5);
  expectRejected("sensor_model/miss", 0.6);
  expectRejected("sensor_model/min", 0.99);
  expectRejected("sensor_model/max", 0.0);
  expectRejected("sensor_model/min_range", -1.0);
  expectRejected("backend", std::string("tpu"));
  expectRejected("raycast", std::string("bvh"));
  expectRejected("sensor/type", std::string("sonar"));
  expectRejected("sensor/range_noise", -0.01);
  expectRejected("sensor/range_noise", std::nan(""));
  expectRejected("sensor/range_noise_quadratic", 2.0);
  expectRejected("queue_size", 0);
  expectRejected("queue_size", 2.5);
  expectRejected("tf_tolerance", -0.1);
  expectRejected("marker_rate", -1.0);
  expectRejected("marker_rate", std::numeric_limits<double>::infinity());
  expectRejected("map_rate", -0.5);
  expectRejected("map_rate", std::nan(""));
  expectRejected("map_rate", std::numeric_limits<double>::infinity());
  expectRejected("map_rate", std::string("1 Hz"));
  expectRejected("latch", 1);
  expectRejected("threads", -1);
  expectRejected("culling/coherence_ttl_scans", 0);
  expectRejected("unknown_band", -0.1);
  expectRejected("sensor_model/max_range", std::numeric_limits<double>::infinity());
  expectRejected("pointcloud_min_z", std::nan(""));
}

TEST(ServerParams, CoreMessagesReadInParameterNames) {
  XmlRpcValue hit;
  set(hit, "sensor_model/hit", 0.4);
  EXPECT_EQ(rejection(hit), "parameter 'sensor_model/hit' must be > 0.5, got 0.400000");
  XmlRpcValue clamp;
  set(clamp, "sensor_model/min", 0.99);
  EXPECT_EQ(rejection(clamp), "parameter 'sensor_model/min' must be below 'sensor_model/max'");
  XmlRpcValue ranges;
  set(ranges, "sensor_model/min_range", 5.0);
  set(ranges, "sensor_model/max_range", 2.0);
  EXPECT_EQ(rejection(ranges),
            "parameter 'sensor_model/max_range' must exceed 'sensor_model/min_range' (or be <= 0)");
  XmlRpcValue band;
  set(band, "unknown_band", 0.5);
  EXPECT_EQ(rejection(band).rfind("parameter 'unknown_band' must be in [0, 0.5)", 0), 0u)
      << rejection(band);
}

TEST(ServerParams, InconsistentPairsNameTheParameter) {
  XmlRpcValue root;
  set(root, "pointcloud_min_z", 2.0);
  set(root, "pointcloud_max_z", 1.0);
  EXPECT_THROW(
      {
        try {
          fragg::ros::parseParameters(root);
        } catch (const fragg::InvalidArgument& e) {
          EXPECT_NE(std::string(e.what()).find("'pointcloud_min_z'"), std::string::npos);
          throw;
        }
      },
      fragg::InvalidArgument);
  XmlRpcValue pinhole;
  set(pinhole, "sensor/type", std::string("pinhole"));  // no hfov/vfov
  EXPECT_THROW(fragg::ros::parseParameters(pinhole), fragg::InvalidArgument);
  XmlRpcValue ranges;
  set(ranges, "sensor_model/min_range", 5.0);
  set(ranges, "sensor_model/max_range", 2.0);
  EXPECT_THROW(fragg::ros::parseParameters(ranges), fragg::InvalidArgument);
  XmlRpcValue occupancy;
  set(occupancy, "occupancy_min_z", 3.0);
  set(occupancy, "occupancy_max_z", 0.0);
  EXPECT_THROW(fragg::ros::parseParameters(occupancy), fragg::InvalidArgument);
  XmlRpcValue not_a_struct(3);
  EXPECT_THROW(fragg::ros::parseParameters(not_a_struct), fragg::InvalidArgument);
}

}  // namespace

namespace {

// The parameters of config/*.yaml files loaded in order, through yaml_to_xmlrpc.py.
XmlRpcValue loadYaml(const std::vector<std::string>& files) {
  std::string cmd = std::string(FRAGG_PYTHON3) + " " + FRAGG_YAML_TO_XMLRPC;
  for (const std::string& f : files) cmd += " " + std::string(FRAGG_CONFIG_DIR) + "/" + f;
  FILE* pipe = popen(cmd.c_str(), "r");
  EXPECT_NE(pipe, nullptr);
  std::string xml;
  char buf[4096];
  for (size_t n; pipe && (n = fread(buf, 1, sizeof buf, pipe)) > 0;) xml.append(buf, n);
  EXPECT_EQ(pipe ? pclose(pipe) : -1, 0) << cmd;
  int offset = 0;
  XmlRpcValue v(xml, &offset);
  EXPECT_TRUE(v.valid()) << xml;
  return v;
}

TEST(ServerParamsConfig, DefaultYamlMatchesTheCoreDefaults) {
  const fragg::ros::ServerParams p = fragg::ros::parseParameters(loadYaml({"default.yaml"}));
  const fragg::ros::ServerParams d = fragg::ros::parseParameters(XmlRpcValue());
  EXPECT_EQ(p.map.resolution_m, d.map.resolution_m);
  EXPECT_EQ(p.map.occupancy.prob_hit, d.map.occupancy.prob_hit);
  EXPECT_EQ(p.map.occupancy.prob_miss, d.map.occupancy.prob_miss);
  EXPECT_EQ(p.map.occupancy.clamp_min, d.map.occupancy.clamp_min);
  EXPECT_EQ(p.map.occupancy.clamp_max, d.map.occupancy.clamp_max);
  EXPECT_EQ(p.map.occupancy.unknown_band, d.map.occupancy.unknown_band);
  EXPECT_EQ(p.sensor.type, d.sensor.type);
  EXPECT_EQ(p.sensor.max_range_m, d.sensor.max_range_m);
  EXPECT_EQ(p.map.height_filter.min_z_m, d.map.height_filter.min_z_m);
  EXPECT_EQ(p.occupancy_max_z_m, d.occupancy_max_z_m);
  EXPECT_EQ(p.queue_size, d.queue_size);
  EXPECT_EQ(p.tf_tolerance_s, d.tf_tolerance_s);
  EXPECT_EQ(p.marker_rate_hz, d.marker_rate_hz);
  EXPECT_EQ(p.map_rate_hz, d.map_rate_hz);
  EXPECT_EQ(p.latch, d.latch);
  EXPECT_EQ(p.color_max_z_m, d.color_max_z_m);
  EXPECT_EQ(p.map.scans.keep, d.map.scans.keep);
  EXPECT_EQ(p.map.scans.max_bytes, d.map.scans.max_bytes);
  EXPECT_EQ(p.map.scans.point_step_m, d.map.scans.point_step_m);
  EXPECT_EQ(p.map.scans.spill_dir, d.map.scans.spill_dir);
  EXPECT_EQ(p.map.dynamic.enabled, d.map.dynamic.enabled);
  EXPECT_EQ(p.map.dynamic.void_probability, d.map.dynamic.void_probability);
  EXPECT_EQ(p.map.dynamic.known_radius_cells, d.map.dynamic.known_radius_cells);
  EXPECT_EQ(p.map.dynamic.rule, d.map.dynamic.rule);
  EXPECT_EQ(p.map.dynamic.decay_log_odds_per_scan, d.map.dynamic.decay_log_odds_per_scan);
  EXPECT_EQ(p.correction.thresholds.min_translation_m, d.correction.thresholds.min_translation_m);
  EXPECT_EQ(p.correction.thresholds.min_rotation_rad, d.correction.thresholds.min_rotation_rad);
  EXPECT_EQ(p.correction.stamp_tolerance_s, d.correction.stamp_tolerance_s);
  EXPECT_EQ(p.correction.path_child_frame, d.correction.path_child_frame);
  EXPECT_EQ(p.correction.subscribe_path, d.correction.subscribe_path);
  EXPECT_EQ(p.collision.unknown_is_occupied, d.collision.unknown_is_occupied);
  EXPECT_EQ(p.collision.margin_m, d.collision.margin_m);
  EXPECT_EQ(p.collision.mesh, d.collision.mesh);
  EXPECT_EQ(p.collision.mesh_scale, d.collision.mesh_scale);
  EXPECT_EQ(p.collision.max_markers, d.collision.max_markers);
  EXPECT_EQ(p.paced_outputs, d.paced_outputs);
  EXPECT_EQ(p.mirror_every_cloud, d.mirror_every_cloud);
  EXPECT_TRUE(d.mirror_every_cloud);
  EXPECT_EQ(p.shares_between_clouds, d.shares_between_clouds);
  EXPECT_TRUE(d.shares_between_clouds);
  EXPECT_EQ(p.file_root, d.file_root);
}

TEST(ServerParamsConfig, ShippedYamlsHoldNoUnknownName) {
  for (const std::vector<std::string>& files : std::vector<std::vector<std::string>>{
           {"default.yaml"}, {"default.yaml", "lidar.yaml"}, {"default.yaml", "depth_camera.yaml"}})
    EXPECT_TRUE(fragg::ros::parseParameters(loadYaml(files)).unknown_parameters.empty())
        << files.back() << ": "
        << fragg::ros::parseParameters(loadYaml(files)).unknown_parameters[0];
}

TEST(ServerParamsConfig, LidarYaml) {
  const fragg::ros::ServerParams p =
      fragg::ros::parseParameters(loadYaml({"default.yaml", "lidar.yaml"}));
  EXPECT_EQ(p.sensor.type, fragg::SensorType::kSpinningLidar);
  EXPECT_EQ(p.sensor.max_range_m, 30.0);
  EXPECT_EQ(p.occupancy_max_z_m, 2.0);
  EXPECT_EQ(p.queue_size, 3);
  EXPECT_EQ(p.marker_rate_hz, 1.0);
  EXPECT_EQ(p.map_rate_hz, 1.0);
}

TEST(ServerParamsConfig, DepthCameraYaml) {
  const fragg::ros::ServerParams p =
      fragg::ros::parseParameters(loadYaml({"default.yaml", "depth_camera.yaml"}));
  EXPECT_EQ(p.sensor.type, fragg::SensorType::kPinhole);
  EXPECT_EQ(p.map.resolution_m, 0.02);
  EXPECT_NEAR(p.sensor.hfov_rad, 58.0 * M_PI / 180.0, 1e-4);
  EXPECT_EQ(p.sensor.max_range_m, 4.0);
}

}  // namespace

// frontiers/*: the defaults are `fragg_map frontiers`' (so that ~get_frontiers answers as the
// CLI does with the same options), every name is read, bad values name the parameter.
TEST(ServerParams, FrontierDefaultsValuesAndRefusals) {
  const fragg::ros::ServerParams d = fragg::ros::parseParameters(XmlRpcValue());
  const fragg::ros::FrontierParams& f = d.frontiers;
  EXPECT_EQ(f.rate_hz, 1.0);
  EXPECT_FALSE(f.filter.any());
  EXPECT_EQ(f.clusters.min_cells, 8u);
  EXPECT_EQ(f.clusters.max_extent_m, 3.0);
  EXPECT_EQ(f.viewpoints, 3);
  EXPECT_EQ(f.views.radii_m, (std::vector<double>{1.5, 3.0}));
  EXPECT_EQ(f.views.heights_m, (std::vector<double>{0.0}));
  EXPECT_EQ(f.views.angles, 12);
  EXPECT_EQ(f.views.clearance_m, 0.3);
  EXPECT_EQ(f.views.sensor.kind, fragg::planning::GainSensor::Kind::kPinhole);
  EXPECT_EQ(f.views.sensor.columns, 64);
  EXPECT_EQ(f.views.sensor.rows, 48);
  EXPECT_EQ(f.views.sensor.max_range_m, 10.0);
  EXPECT_EQ(f.max_marker_cells, 200000);
  EXPECT_EQ(f.coarse_cells, 0) << "from the LiDAR's beam spacing";
  EXPECT_FALSE(f.gain.has_value()) << "auto: coverage on a coarse grid, entropy on map cells";
  EXPECT_EQ(f.deadline_s, 0.0);

  XmlRpcValue root;
  XmlRpcValue lo, hi, radii;
  lo[0] = -1.0, lo[1] = -2.0, lo[2] = 0;  // an int among doubles
  hi[0] = 1.0, hi[1] = 2.0, hi[2] = 3.0;
  radii[0] = 2.0;
  set(root, "frontiers/rate_hz", 5);
  set(root, "frontiers/box_min", lo);
  set(root, "frontiers/box_max", hi);
  set(root, "frontiers/min_z", 0.5);
  set(root, "frontiers/min_obstacle_distance", 0.2);
  set(root, "frontiers/min_cluster", 20);
  set(root, "frontiers/max_extent", 0.0);
  set(root, "frontiers/viewpoints", 0);
  set(root, "frontiers/radii", radii);
  set(root, "frontiers/angles", 6);
  set(root, "frontiers/clearance", 0.0);
  set(root, "frontiers/sensor/type", std::string("lidar"));
  set(root, "frontiers/sensor/rows", 8);
  set(root, "frontiers/sensor/max_range", 20.0);
  set(root, "frontiers/max_marker_cells", 1000);
  set(root, "frontiers/coarse_cells", 4);
  set(root, "frontiers/gain", std::string("entropy"));
  set(root, "frontiers/deadline_s", 2.5);
  const fragg::ros::FrontierParams p = fragg::ros::parseParameters(root).frontiers;
  EXPECT_EQ(p.rate_hz, 5.0);
  EXPECT_TRUE(p.filter.use_box);
  EXPECT_EQ(p.filter.box_min_m, Eigen::Vector3d(-1, -2, 0));
  EXPECT_EQ(p.filter.box_max_m, Eigen::Vector3d(1, 2, 3));
  EXPECT_TRUE(p.filter.use_height);
  EXPECT_EQ(p.filter.min_z_m, 0.5);
  EXPECT_GT(p.filter.max_z_m, 1e6) << "max_z left open";
  EXPECT_EQ(p.filter.min_obstacle_distance_m, 0.2);
  EXPECT_EQ(p.clusters.min_cells, 20u);
  EXPECT_EQ(p.clusters.max_extent_m, 0.0);
  EXPECT_EQ(p.viewpoints, 0);
  EXPECT_EQ(p.views.top_k, 1);
  EXPECT_EQ(p.views.radii_m, (std::vector<double>{2.0}));
  EXPECT_EQ(p.views.angles, 6);
  EXPECT_EQ(p.views.clearance_m, 0.0);
  EXPECT_EQ(p.views.sensor.kind, fragg::planning::GainSensor::Kind::kLidar);
  EXPECT_EQ(p.views.sensor.columns, 360) << "the lidar's own default, as the CLI's";
  EXPECT_EQ(p.views.sensor.rows, 8);
  EXPECT_EQ(p.views.sensor.max_range_m, 20.0);
  EXPECT_EQ(p.max_marker_cells, 1000);
  EXPECT_EQ(p.coarse_cells, 4);
  ASSERT_TRUE(p.gain.has_value());
  EXPECT_EQ(*p.gain, fragg::planning::ViewpointGain::kEntropy);
  EXPECT_EQ(p.deadline_s, 2.5);

  expectRejected("frontiers/rate_hz", 0.0);
  expectRejected("frontiers/coarse_cells", 3);
  expectRejected("frontiers/coarse_cells", -1);
  expectRejected("frontiers/gain", std::string("bits"));
  expectRejected("frontiers/deadline_s", -1.0);
  expectRejected("frontiers/deadline_s", std::numeric_limits<double>::quiet_NaN());
  expectRejected("frontiers/rate_hz", std::numeric_limits<double>::infinity());
  expectRejected("frontiers/min_cluster", 0);
  expectRejected("frontiers/max_extent", -1.0);
  expectRejected("frontiers/viewpoints", -1);
  expectRejected("frontiers/angles", 0);
  expectRejected("frontiers/clearance", -0.1);
  expectRejected("frontiers/min_obstacle_distance", -0.1);
  expectRejected("frontiers/max_marker_cells", -1);
  expectRejected("frontiers/radii", 1.0);  // not a list
  XmlRpcValue zero;
  zero[0] = 0.0;
  expectRejected("frontiers/radii", zero);
  expectRejected("frontiers/box_min", hi);  // without box_max
  XmlRpcValue band;
  set(band, "frontiers/min_z", 2.0);
  set(band, "frontiers/max_z", 1.0);
  EXPECT_NE(rejection(band).find("'frontiers/min_z'"), std::string::npos) << rejection(band);
  XmlRpcValue inverted;
  set(inverted, "frontiers/box_min", hi);
  set(inverted, "frontiers/box_max", lo);
  EXPECT_NE(rejection(inverted).find("'frontiers/box_min'"), std::string::npos);
  for (const auto& [name, value] :
       std::vector<std::pair<std::string, XmlRpcValue>>{{"frontiers/sensor/type", "sonar"},
                                                        {"frontiers/sensor/hfov", 4.0},
                                                        {"frontiers/sensor/columns", 0},
                                                        {"frontiers/sensor/max_range", -1.0}}) {
    XmlRpcValue bad;
    set(bad, name, value);
    EXPECT_NE(rejection(bad).find("'frontiers/sensor"), std::string::npos)
        << name << ": " << rejection(bad);
  }
}
