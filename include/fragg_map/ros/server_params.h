// The map server's parameters: MapParams and the sensor model (the core's structs, where the
// defaults live) plus what only the ROS server needs. Names follow octomap_server where the
// meaning is the same; config/default.yaml lists them all.
#pragma once

#include <ros/node_handle.h>
#include <xmlrpcpp/XmlRpcValue.h>

#include <limits>
#include <optional>
#include <string>
#include <vector>

#include "fragg_map/map_params.h"
#include "fragg_map/planning/frontier_cells.h"
#include "fragg_map/planning/frontier_clusters.h"
#include "fragg_map/planning/viewpoints.h"
#include "fragg_map/ros/pose_correction.h"
#include "fragg_map/sensor_model.h"

namespace fragg::ros {

/// Loop-closure correction (~correct_poses, corrected_path): correction/*.
struct CorrectionParams {
  /// corrected_path moves a scan only when its pose changed beyond one of these.
  PoseThresholds thresholds;  ///< correction/min_translation [m], correction/min_rotation [rad]
  double stamp_tolerance_s = 0.001;  ///< a stamp names the kept scan nearest to it within this
  /// Empty: corrected_path gives sensor poses. Else the frame whose pose it gives (base_link);
  /// the sensor pose is that pose times tf child_frame -> cloud frame at the scan's stamp.
  std::string path_child_frame;
  bool subscribe_path = true;  ///< subscribe corrected_path
};

/// ~check_collision: collision/*. The request may override the two options.
struct CollisionParams {
  bool unknown_is_occupied = false;  ///< collision/unknown_is_occupied
  double margin_m = 0.0;             ///< collision/margin [m], >= 0
  /// collision/mesh: absolute path of an OBJ (the robot; origin = the pose a request gives),
  /// read at start-up; "": requests of shape "mesh" must carry their own triangles.
  std::string mesh;
  double mesh_scale = 1.0;  ///< collision/mesh_scale: OBJ units -> metres (> 0)
  int max_markers = 500;    ///< collision/max_markers: poses drawn on `collisions` (>= 0)
};

/// Frontier topics (`frontiers`, `frontier_cells`) and ~get_frontiers: frontiers/*.
struct FrontierParams {
  /// frontiers/rate_hz: most topic updates per second (steady clock), > 0; an update happens
  /// only while someone subscribes and the map changed.
  double rate_hz = 1.0;
  /// frontiers/box_min, frontiers/box_max ([x, y, z], both or neither), frontiers/min_z,
  /// frontiers/max_z (either one turns the band on), frontiers/min_obstacle_distance [m].
  planning::FrontierFilter filter;
  planning::ClusterOptions clusters;  ///< frontiers/min_cluster, frontiers/max_extent [m]
  /// frontiers/radii, heights [m lists], angles, clearance [m]; the gain sensor
  /// frontiers/sensor/type (pinhole | lidar), columns, rows, hfov, vfov, elevation_min,
  /// elevation_max [rad], max_range [m]. top_k is viewpoints below (at least 1).
  planning::ViewpointOptions views;
  int viewpoints = 3;  ///< frontiers/viewpoints: best k per cluster on `frontiers` (0: none)
  /// frontiers/max_marker_cells: most frontier cells drawn on `frontiers` and sent on
  /// `frontier_cells` (an even subsample beyond it, logged); >= 0.
  int max_marker_cells = 200000;
  /// frontiers/coarse_cells: ~get_frontiers on a grid of N x N x N map cells (1, 2, 4 or 8;
  /// planning/coarse_map.h: a coarse cell is free when a cell is, unknown when all are), so
  /// that the gaps between a LiDAR's beams are not frontiers; the map's lock is held only while
  /// the coarse copy is made (of the query's box, when it has one). 1: the map's own cells (the
  /// CLI's default). 0 (the default): from the beam spacing of the first clouds received
  /// (planning/beam_spacing.h) at their far range, capped by sensor_model/max_range
  /// (coarseCellsForBeams); 1 until a LiDAR-like cloud came.
  int coarse_cells = 0;
  /// frontiers/gain: the viewpoints' gain, "entropy" or "coverage" (planning::ViewpointGain);
  /// nullopt ("auto", the default): coverage on a coarse grid, entropy on the map's own cells
  /// (the topics, always on the map's cells, use views.gain: this one when given, else entropy).
  std::optional<planning::ViewpointGain> gain;
  /// frontiers/deadline_s: ~get_frontiers gives up after this long (success false, saying so);
  /// 0: no deadline.
  double deadline_s = 0.0;
};

/// octomap_server's parameters of the same name and meaning (docs/ros.md: "octomap_server ->
/// fragg_map"; launch/octomap_compat.launch loads an octomap_server YAML unchanged).
struct OctomapCompatParams {
  /// The robot's base frame: the ground plane is sought in it (filter_ground).
  std::string base_frame_id = "base_footprint";
  /// Ground points (PCL plane segmentation in base_frame_id) only clear (ground_filter.h).
  bool filter_ground = false;
  double ground_distance_m = 0.04;        ///< ground_filter/distance: plane inlier distance
  double ground_angle_rad = 0.15;         ///< ground_filter/angle: plane normal vs z at most
  double ground_plane_distance_m = 0.07;  ///< ground_filter/plane_distance: |d| at most
  bool filter_speckles = false;  ///< views leave out occupied cells with no occupied neighbour
  bool height_map = true;        ///< markers coloured by height, else `color`
  /// Occupied markers coloured by the points' rgb/rgba (CellColors); height_map wins.
  bool colored_map = false;
  float color_rgba[4] = {0.0f, 0.0f, 1.0f, 1.0f};  ///< color/r|g|b|a with height_map false
  bool incremental_2D_projection = false;  ///< projected_map patches only the changed columns
  bool compress_map =
      true;  ///< octomap_full pruned (equal sibling leaves merged), as octomap_server
  /// ~clear_bbx's rule: true (octomap_server's) sets the observed cells in the box free at the
  /// lower clamp; false makes them unknown, as ~clear_bbox does.
  bool clear_bbx_free = true;
  /// projected_map/octomap_bounds: the grid spans octomap_server's bounds (its upper-face key,
  /// the origin inside; octomapServerGridSpan) instead of the observed cells' bounds.
  bool projected_map_octomap_bounds = false;
  /// Map loaded at start-up (.fgm or .bt); also the node's first argument.
  std::string map_file;
};

struct ServerParams {
  static constexpr double kDefaultMaxRangeM = 100.0;  ///< sensor_model/max_range's default
  /// resolution, sensor_model/hit|miss|min|max, backend, raycast; keep_scans and scan_store/*
  /// (map.scans: the server keeps scans by default, the core does not); pointcloud_min_z|max_z
  /// (map.height_filter: points outside [min, max] map-frame z are not inserted).
  fragg::MapParams map = withKeptScans();
  /// sensor/type|hfov|vfov, sensor_model/min_range|max_range. The server's max_range defaults
  /// to kDefaultMaxRangeM (the core's and octomap_server's: -1, no limit; <= 0 still means no
  /// limit when given), so that a few far outliers cannot stretch the map.
  fragg::SensorModel sensor = fragg::SensorModel::autoFromCloud(0.0, kDefaultMaxRangeM);
  std::string frame_id = "map";
  /// file_root: the folder ~save_map, ~load_map, ~truncate and ~merge read and write in
  /// (server/file_root.h); "": $ROS_HOME/fragg_map, else ~/.ros/fragg_map. Created at start-up.
  /// map_file (the operator's start-up map) is not restricted to it.
  std::string file_root;
  /// Heights projected into projected_map.
  double occupancy_min_z_m = -std::numeric_limits<double>::infinity();
  double occupancy_max_z_m = std::numeric_limits<double>::infinity();
  bool latch =
      true;  ///< latched topics (octomap_server's default); full markers to late subscribers
  bool publish_free_space = false;  ///< free_cells_vis_array
  int queue_size = 5;               ///< clouds waiting for insertion; the oldest are dropped
  double tf_tolerance_s = 0.5;      ///< how long a cloud may wait for its transform
  /// Most marker updates per second (steady clock); 0: one after every cloud. Changed blocks
  /// accumulate between updates (BlockMeta::changed_at), so none is lost.
  double marker_rate_hz = 0.0;
  /// Most updates per second (steady clock) of the whole-map outputs (occupied_cells,
  /// octomap_point_cloud_centers, projected_map, octomap_binary, octomap_full); 0: after every
  /// cloud. Skipped clouds cost nothing there (the output cache catches up from the revision
  /// it last saw); reset, load, clear and corrections publish at once.
  double map_rate_hz = 0.0;
  /// paced_outputs: with marker_rate / map_rate > 0, the work behind an update is spread over
  /// the clouds of its period (after every cloud a share of the changed marker chunks is sent
  /// and a share of the changed blocks goes into the output cache; each within a period of its
  /// change) instead of coming as one burst when the update is due. false: the burst.
  bool paced_outputs = true;
  /// mirror_every_cloud: on a CUDA map with paced outputs, the outputs' mask mirror takes each
  /// cloud's changed blocks in after that cloud's outputs, when no other cloud waits (between
  /// clouds: CloudPipeline::BetweenFn), and a cloud's take-ins read it as that left it (one
  /// insertion behind) instead of syncing a period's changes on the cloud's path (the
  /// default: on an H100, W1 5 cm at 10 Hz, 23 clouds over 20 ms against 64). false: once a
  /// period, on the path of the cloud whose take-in is due (11-17 ms on an H100 at W1 5 cm).
  /// (Before 2026-12-08 true synced on every cloud's path, which made more clouds late.)
  bool mirror_every_cloud = true;
  /// shares_between_clouds: with paced outputs that someone reads, the paced shares are worked
  /// out between clouds (when no cloud waits; on a CUDA map right after the mirror's sync)
  /// instead of on each cloud's path: the output cache's (recomputing the blocks a publication
  /// listed, gathering the next occupied cloud message: staging, nothing published) and the
  /// markers' next share, built from the map as it is then (on a CUDA map the mirror state the
  /// next cloud's take-ins would read; on a CPU map one insertion older) and published on the
  /// next cloud's path (publications stay on a cloud's path). A cloud after which no gap ran
  /// them takes them on its path as before; a cloud arriving meanwhile waits for them
  /// (queue_ms). false: always on the path.
  bool shares_between_clouds = true;
  /// trace_csv: a file that gets one row per cloud received (its outcome and where its time
  /// went: queue, conversion, tf, insertion, outputs); empty: none.
  std::string trace_csv;
  /// markers/chunk_blocks: blocks per side of the chunk one marker of the marker topics draws
  /// (1: one marker per 8x8x8 block); a change redraws its chunk.
  int marker_chunk_blocks = 4;
  double color_min_z_m = -1.0;  ///< marker colour ramp (markers/color_min_z)
  double color_max_z_m = 4.0;   ///< marker colour ramp (markers/color_max_z)
  CorrectionParams correction;
  CollisionParams collision;
  FrontierParams frontiers;
  OctomapCompatParams octomap;
  /// Names in the namespace that no parameter reads (misspelled, or of another program), each
  /// with a hint ("sensor_model/hitt (did you mean sensor_model/hit?)"); readParameters warns
  /// once naming them all.
  std::vector<std::string> unknown_parameters;

  /// The core's defaults with keep_scans on and a 2 GiB budget (scan_store/max_mb 2048).
  static fragg::MapParams withKeptScans() {
    fragg::MapParams m;
    m.scans.keep = true;
    m.scans.max_bytes = size_t{2048} << 20;
    return m;
  }
};

/// Fills ServerParams from a struct of parameters (the private namespace as one
/// XmlRpcValue; absent names keep their defaults) and validates every value (the core's
/// fields through the core's validate()). Throws fragg::InvalidArgument naming the parameter
/// ('sensor_model/hit') for a wrong type or an invalid value.
ServerParams parseParameters(const XmlRpc::XmlRpcValue& params);

/// Reads the node's private namespace and parses it as above.
ServerParams readParameters(const ::ros::NodeHandle& private_nh);

}  // namespace fragg::ros
