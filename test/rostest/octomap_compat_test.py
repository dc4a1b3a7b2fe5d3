#!/usr/bin/python3
"""rostest of fragg_map as a drop-in for octomap_server (launch/octomap_compat.launch, node
named octomap_server, parameters from an octomap_server YAML): every row of docs/ros.md's
"octomap_server -> fragg_map" table. One synthetic cloud from a sensor 1 m above the map
origin: a wall at x = 3 m, a point beyond sensor_model/max_range, points below
pointcloud_min_z and above pointcloud_max_z, one above occupancy_max_z and one below
occupancy_min_z. Further server processes (the node's executable, started here, each in a
namespace of its own: ExtraServer) check the start-up map (map_file, first argument), the
warning that names unknown parameters, filter_ground and filter_speckles.

docs/ros.md row -> test:
  cloud_in, pointcloud_min_z/max_z, max_range                  test_03
  occupied_cells_vis_array, frame_id, resolution, height_map/color  test_01
  free_cells_vis_array, publish_free_space                      test_02
  octomap_point_cloud_centers                                   test_04
  projected_map, latch, octomap_server's grid bounds            test_05
  occupancy_min_z/max_z (markers, clouds, projected_map)        test_03, test_05
  sensor_model/hit, miss, min, max                              test_05a
  ~clear_bbx (known cells in the box set free, clear_bbx_free)  test_06
  ~reset                                                        test_07
  ~load_map (.bt, .fgm)                                         test_08
  map_file / first argument                                     test_09
  compress_map and every other name of the YAML, unknown names  test_10
  octomap_binary / octomap_full topics and services             test_11
  base_frame_id, filter_ground, ground_filter/*                 test_12
  filter_speckles                                               test_13
  sensor_model/free_cut_cell (a ray cut at max_range frees the cut point's cell)  test_16
  dynamic_reconfigure (~set_parameters, octomap_server's names)  test_17
  free_cells_vis_array advertised always; no corrected_path subscription  test_18
A new row is one test function: ExtraServer(self, name, {parameters}) gives a server of its
own with those parameters over the YAML's, .insert(points) feeds it a cloud, .occupied() /
.cells() / .last(topic) read what it made."""
import os
import shutil
import signal
import struct
import subprocess
import tempfile
import time
import unittest

import array
import math

import genmsg
import genmsg.gentools
import genmsg.msg_loader
import rospkg
import rosparam
import rospy
import rostest
import sensor_msgs.point_cloud2 as pc2
from catkin.find_in_workspaces import find_in_workspaces
from geometry_msgs.msg import Point, TransformStamped
from nav_msgs.msg import OccupancyGrid
from sensor_msgs.msg import PointCloud2
from std_msgs.msg import Header
from std_srvs.srv import Empty
from tf2_msgs.msg import TFMessage
from visualization_msgs.msg import Marker, MarkerArray

from fragg_map.srv import BoundingBoxQuery, GetStats, LoadMap, Reset, SaveMap

import fgm_cells
from map_server_checks import wait_for

NS = "/octomap_server/"
RES = 0.1
SENSOR_Z = 1.0  # the sensor frame's height in the map frame


def key(x, y, z):
    return (int(x // RES), int(y // RES), int(z // RES))


def scene_points():
    """Sensor-frame points: the wall (x = 3 m, map z 0.55..1.45), beyond range, not inserted
    (outside the pointcloud height band), high and low (outside the occupancy band)."""
    wall = [(3.05, -0.45 + 0.1 * i, -0.45 + 0.1 * j) for i in range(10) for j in range(10)]
    beyond = [(8.05, 0.05, 0.05)]        # 8 m > max_range 5 m: only clears up to 5 m
    too_low = [(2.05, 1.05, -3.05)]      # map z -2.05 < pointcloud_min_z -1: not inserted
    too_high = [(2.05, 1.05, 2.55)]      # map z 3.55 > pointcloud_max_z 3: not inserted
    high = [(2.05, -1.05, 1.55)]         # map z 2.55 > occupancy_max_z 2: 3D only
    low = [(2.05, 2.05, -1.45)]          # map z -0.45 < occupancy_min_z 0: 3D only
    return wall, beyond, too_low + too_high, high + low


def floor_scene():
    """Sensor-frame points of a floor (map z 0.02, 600 points from 1 to 4 m ahead), a wall
    behind it (x = 4.55 m) and one point alone in the air (a speckle)."""
    floor = [(1.05 + 0.1 * i, -0.95 + 0.1 * j, 0.02 - SENSOR_Z)
             for i in range(30) for j in range(20)]
    wall = [(4.55, -0.95 + 0.1 * i, -0.45 + 0.1 * j) for i in range(20) for j in range(10)]
    speckle = [(2.05, -2.05, 0.55)]
    return floor, wall, speckle


def fixed_log_odds(p):
    """The map's fixed-point log-odds of probability p (1/1024 units, rounded half away)."""
    v = math.log(p / (1.0 - p)) * 1024.0
    return int(math.floor(v + 0.5)) if v >= 0 else -int(math.floor(-v + 0.5))


def cell_log_odds(path):
    """{(x, y, z) voxel key: log_odds_fx} of the observed cells of a .fgm file."""
    blocks, _ = fgm_cells.read_blocks(path)
    cells = {}
    edge = fgm_cells.BLOCK_EDGE
    for (bx, by, bz), raw in blocks.items():
        log_odds = array.array("h", raw)[1::2]
        for i, v in enumerate(log_odds):
            if v != fgm_cells.UNOBSERVED:
                cells[(bx * edge + i % edge, by * edge + (i // edge) % edge,
                       bz * edge + i // (edge * edge))] = v
    return cells


def octomap_server_span(lo, hi, res):
    """octomap_server's projected_map keys on one axis for observed keys [lo, hi]: the leaves'
    faces (liboctomap's calcMinMax), widened to the origin (its zero padding), keyed as a
    float point3d (coordToKeyChecked)."""
    def f32(v):
        return struct.unpack("f", struct.pack("f", v))[0]
    half = res / 2.0
    min_face = (lo + 0.5) * res - half
    max_face = ((hi + 0.5) * res - half) + res
    factor = 1.0 / res
    return (math.floor(factor * f32(min(min_face, -0.0))),
            math.floor(factor * f32(max(max_face, 0.0))))


def yaml_params():
    with open(rospy.get_param("~yaml")) as f:
        return rosparam.load_str(f.read(), "")[0][0]


def occupied_keys(cloud):
    return {key(x, y, z) for x, y, z in pc2.read_points(cloud, ("x", "y", "z"), skip_nans=True)}


class OctomapCompatTest(unittest.TestCase):
    @classmethod
    def setUpClass(cls):
        rospy.init_node("octomap_compat_test")
        cls.tmp = tempfile.mkdtemp(prefix="fragg_map_octomap_compat_")
        cls.procs = []
        cls.last = {}
        cls.arrays = []
        for topic, kind in (("occupied_cells_vis_array", MarkerArray),
                            ("free_cells_vis_array", MarkerArray),
                            ("octomap_point_cloud_centers", PointCloud2),
                            ("occupied_cells", PointCloud2)):
            rospy.Subscriber("/" + topic, kind, cls.keep(topic), queue_size=20)
        rospy.Subscriber("/occupied_cells_vis_array", MarkerArray, cls.arrays.append,
                         queue_size=20)
        transforms = []
        for child, z in (("sensor", SENSOR_Z), ("base_link", 0.0)):  # base_link: the YAML's
            tf = TransformStamped()
            tf.header.frame_id = "map"
            tf.child_frame_id = child
            tf.transform.translation.z = z
            tf.transform.rotation.w = 1.0
            transforms.append(tf)
        cls.tf_pub = rospy.Publisher("/tf_static", TFMessage, queue_size=1, latch=True)
        cls.tf_pub.publish(TFMessage(transforms))
        for name in ("get_stats", "save_map", "load_map", "reset", "reset_map", "clear_bbx"):
            rospy.wait_for_service(NS + name, timeout=60)
        cls.get_stats = rospy.ServiceProxy(NS + "get_stats", GetStats)
        cls.cloud_pub = rospy.Publisher("/cloud_in", PointCloud2, queue_size=2)
        wait_for(lambda: cls.cloud_pub.get_num_connections() > 0, 20, "the server on cloud_in")
        cls.publish_scene()
        wait_for(lambda: cls.get_stats().stats.scans >= 1, 30, "the cloud inserted")
        wait_for(lambda: all(t in cls.last for t in ("occupied_cells_vis_array",
                                                      "octomap_point_cloud_centers",
                                                      "occupied_cells")), 20, "the map topics")
        # The scan count rises before the outputs of the cloud go out, and a subscriber that
        # connected before the insertion first gets the empty map: wait for the cloud's markers.
        def markers_with_points(topic):
            msg = cls.last.get(topic)
            return msg is not None and any(m.points for m in msg.markers)
        wait_for(lambda: markers_with_points("occupied_cells_vis_array") and
                 markers_with_points("free_cells_vis_array"), 20, "the cloud's markers")

    @classmethod
    def keep(cls, topic):
        return lambda msg: cls.last.__setitem__(topic, msg)

    @classmethod
    def publish_scene(cls):
        wall, beyond, not_inserted, outside_band = scene_points()
        header = Header(frame_id="sensor", stamp=rospy.Time.now())
        cls.cloud_pub.publish(pc2.create_cloud_xyz32(header, wall + beyond + not_inserted +
                                                     outside_band))

    @classmethod
    def tearDownClass(cls):
        for proc in cls.procs:
            if proc.poll() is None:
                proc.send_signal(signal.SIGINT)
                try:
                    proc.wait(10)
                except subprocess.TimeoutExpired:
                    proc.kill()
        shutil.rmtree(cls.tmp, ignore_errors=True)

    def stats(self, ns=NS):
        res = rospy.ServiceProxy(ns + "get_stats", GetStats)()
        self.assertTrue(res.success, res.message)
        return res.stats

    # ---- parameters of the YAML ----
    def test_01_frame_resolution_and_flat_colour(self):
        """frame_id, resolution, height_map false with color/*: every marker cell red (the
        marker's colour, no per-point colours: as octomap_server draws it)."""
        markers = [m for m in self.last["occupied_cells_vis_array"].markers
                   if m.action == Marker.ADD]
        self.assertTrue(markers)
        for m in markers:
            self.assertEqual(m.header.frame_id, "map")
            self.assertAlmostEqual(m.scale.x, RES)
            self.assertEqual(len(m.colors), 0)
            c = m.color
            self.assertEqual((c.r, c.g, c.b, c.a), (1.0, 0.0, 0.0, 1.0))

    def test_02_publish_free_space(self):
        wait_for(lambda: "free_cells_vis_array" in self.last, 10, "free_cells_vis_array")
        self.assertTrue(any(m.points for m in self.last["free_cells_vis_array"].markers))

    def test_03_max_range_and_height_bands(self):
        """max_range and pointcloud_min_z/max_z decide what is inserted (the saved map holds
        the wall and the high and low points as hits, nothing of the others);
        occupancy_min_z/max_z what is shown, as octomap_server: the high and low cells are in
        neither the occupied cloud, its alias nor the occupied markers."""
        path = os.path.join(self.tmp, "height_bands.fgm")
        self.assertTrue(rospy.ServiceProxy(NS + "save_map", SaveMap)(path).success)
        in_map = cell_log_odds(path)
        wall, beyond, not_inserted, outside_band = scene_points()
        for x, y, z in wall + outside_band:
            self.assertGreater(in_map.get(key(x, y, z + SENSOR_Z), -1), 0)
        for x, y, z in beyond + not_inserted:
            self.assertNotIn(key(x, y, z + SENSOR_Z), in_map)
        shown = [occupied_keys(self.last[t])
                 for t in ("occupied_cells", "octomap_point_cloud_centers")]
        shown.append({key(p.x, p.y, p.z) for m in self.last["occupied_cells_vis_array"].markers
                      if m.action == Marker.ADD for p in m.points})
        for occupied in shown:
            for x, y, z in wall:
                self.assertIn(key(x, y, z + SENSOR_Z), occupied)
            self.assertEqual(len(occupied), len(wall))

    def test_04_point_cloud_centers_alias_of_occupied_cells(self):
        centers = self.last["octomap_point_cloud_centers"]
        cells = self.last["occupied_cells"]
        self.assertEqual(centers.header.frame_id, "map")
        self.assertEqual(occupied_keys(centers), occupied_keys(cells))
        self.assertEqual(centers.width * centers.height, cells.width * cells.height)

    def test_05_projected_map_reaches_a_late_subscriber_unlatched(self):
        """latch false (the YAML): a subscriber arriving after the last update still gets the
        grid; occupancy_min_z/max_z: the high point is not projected, the wall is."""
        grids = []
        sub = rospy.Subscriber("/projected_map", OccupancyGrid, grids.append)
        wait_for(lambda: grids, 10, "projected_map for a late subscriber")
        sub.unregister()
        grid = grids[0]
        self.assertAlmostEqual(grid.info.resolution, RES, places=6)

        def at(x, y):
            i = int((x - grid.info.origin.position.x) / RES)
            j = int((y - grid.info.origin.position.y) / RES)
            return grid.data[j * grid.info.width + i]
        self.assertEqual(at(3.05, 0.05), 100)
        self.assertNotEqual(at(2.05, -1.05), 100)  # above occupancy_max_z
        self.assertNotEqual(at(2.05, 2.05), 100)   # below occupancy_min_z
        self.assertEqual(at(1.55, 0.05), 0)  # the rays' free cells below 2 m
        # projected_map/octomap_bounds (octomap_compat.launch): octomap_server's grid for the
        # map's observed cells, as its handlePreNodeTraversal computes it.
        path = os.path.join(self.tmp, "projected.fgm")
        self.assertTrue(rospy.ServiceProxy(NS + "save_map", SaveMap)(path).success)
        keys = list(cell_log_odds(path))
        x0, x1 = octomap_server_span(min(k[0] for k in keys), max(k[0] for k in keys), RES)
        y0, y1 = octomap_server_span(min(k[1] for k in keys), max(k[1] for k in keys), RES)
        self.assertEqual((grid.info.width, grid.info.height), (x1 - x0 + 1, y1 - y0 + 1))
        self.assertAlmostEqual(grid.info.origin.position.x, x0 * RES, places=6)
        self.assertAlmostEqual(grid.info.origin.position.y, y0 * RES, places=6)
        self.assertLessEqual(x0, 0)  # the origin's cell is always inside
        self.assertGreaterEqual(y1, 0)

    def test_05a_sensor_model_probabilities(self):
        """sensor_model/hit, miss, min, max (the YAML's, none of them the default): the saved
        map's occupancy model, a wall cell hit once and a cell its ray crossed once."""
        model = yaml_params()["sensor_model"]
        path = os.path.join(self.tmp, "sensor_model.fgm")
        self.assertTrue(rospy.ServiceProxy(NS + "save_map", SaveMap)(path).success)
        with open(path, "rb") as f:
            header = f.read(64)
        self.assertEqual(struct.unpack_from("<4d", header, 24),
                         (model["hit"], model["miss"], model["min"], model["max"]))
        cells = cell_log_odds(path)
        self.assertEqual(cells[key(3.05, 0.05, 1.05)], fixed_log_odds(model["hit"]))
        self.assertEqual(cells[key(1.55, 0.05, 1.05)], fixed_log_odds(model["miss"]))

    # ---- services ----
    def test_06_clear_bbx_with_octomap_msgs_type(self):
        """~clear_bbx has octomap_msgs/BoundingBoxQuery's md5sum (computed from the definition
        text of the stand-in, field for field octomap_msgs') and clears the box."""
        ctx = genmsg.MsgContext.create_default()
        path = os.path.join(rospy.get_param("~standin"), "srv", "BoundingBoxQuery.srv")
        with open(path) as f:
            spec = genmsg.msg_loader.load_srv_from_string(ctx, f.read(),
                                                          "octomap_msgs/BoundingBoxQuery")
        search = {"geometry_msgs": [os.path.join(rospkg.RosPack().get_path("geometry_msgs"), "msg")]}
        genmsg.msg_loader.load_depends(ctx, spec.request, search)
        genmsg.msg_loader.load_depends(ctx, spec.response, search)
        octomap_md5 = genmsg.gentools.compute_md5(ctx, spec)
        self.assertEqual(BoundingBoxQuery._md5sum, octomap_md5)
        saved = os.path.join(self.tmp, "before_clear.fgm")
        self.assertTrue(rospy.ServiceProxy(NS + "save_map", SaveMap)(saved).success)
        self.assertTrue(rospy.ServiceProxy(NS + "save_map", SaveMap)(
            os.path.join(self.tmp, "before_clear.bt")).success)
        before = self.stats().known_voxels
        rospy.ServiceProxy(NS + "clear_bbx", BoundingBoxQuery)(Point(2.9, -1, 0), Point(3.2, 1, 2))
        # octomap_server's rule (clear_bbx_free, the default): the known cells in the box become
        # free at the clamping minimum (sensor_model/min); none becomes unknown, none outside
        # changes. Cells within one of the box's faces are not judged (float rounding of key()).
        self.assertEqual(self.stats().known_voxels, before)
        after = os.path.join(self.tmp, "after_clear.fgm")
        self.assertTrue(rospy.ServiceProxy(NS + "save_map", SaveMap)(after).success)
        old, new = cell_log_odds(saved), cell_log_odds(after)
        self.assertEqual(set(old), set(new))
        lo, hi = key(2.9, -1, 0), key(3.2, 1, 2)
        free_fx = fixed_log_odds(yaml_params()["sensor_model"]["min"])
        inside = outside = 0
        for k, v in old.items():
            if all(lo[i] + 1 <= k[i] <= hi[i] - 1 for i in range(3)):
                inside += 1
                self.assertEqual(new[k], free_fx, "cell %s in the box" % (k,))
            elif any(k[i] < lo[i] - 1 or k[i] > hi[i] + 1 for i in range(3)):
                outside += 1
                self.assertEqual(new[k], v, "cell %s outside the box" % (k,))
        self.assertGreater(inside, 20)  # the wall's cells (x 3.0-3.1) and free cells before it
        self.assertGreater(outside, 100)
        wait_for(lambda: key(3.05, 0.05, 1.05) not in occupied_keys(self.last["occupied_cells"]),
                 10, "the wall gone from occupied_cells")
        with self.assertRaises(rospy.ServiceException):  # an inverted box: a failed call
            rospy.ServiceProxy(NS + "clear_bbx", BoundingBoxQuery)(Point(1, 1, 1), Point(0, 0, 0))

    def test_07_reset_std_srvs_empty_and_stats_follow(self):
        n = len(self.arrays)
        rospy.ServiceProxy(NS + "reset", Empty)()
        s = self.stats()
        self.assertEqual((s.known_voxels, s.scans, s.points, s.dropped_clouds), (0, 0, 0, 0))
        wait_for(lambda: any(m.action == Marker.DELETEALL for a in self.arrays[n:]
                             for m in a.markers), 10, "a full marker republish after reset")
        res = rospy.ServiceProxy(NS + "reset_map", Reset)()  # fragg's richer reset
        self.assertTrue(res.success, res.message)
        self.assertIn("resident memory", res.message)

    def test_08_load_map_reads_bt_and_fgm_stats_follow(self):
        load = rospy.ServiceProxy(NS + "load_map", LoadMap)
        res = load(os.path.join(self.tmp, "before_clear.fgm"))
        self.assertTrue(res.success, res.message)
        s = self.stats()
        known = s.known_voxels
        self.assertGreater(known, 0)
        self.assertEqual(s.scans, 1)  # the file's count
        rospy.ServiceProxy(NS + "reset", Empty)()
        res = load(os.path.join(self.tmp, "before_clear.bt"))
        self.assertTrue(res.success, res.message)
        s = self.stats()
        self.assertEqual(s.known_voxels, known)  # a .bt keeps every observed cell
        self.assertEqual(s.scans, 0)

    # ---- start-up map and parameter names, in servers started here ----
    def start_server(self, name, args=(), params=None):
        """A server in a namespace of its own (its public topics and services, octomap_binary
        for one, must not replace the main server's); its private namespace is
        /NAME/NAME/."""
        private = "/%s/%s/" % (name, name)
        # Its maps are saved under the test's folder: the file services' root (file_root).
        params = dict(params or {})
        params.setdefault("file_root", self.tmp)
        rosparam.upload_params(private, params)
        exe = find_in_workspaces(["libexec"], project="fragg_map", path="fragg_map_server",
                                 first_match_only=True)
        self.assertTrue(exe, "fragg_map_server is not in the workspace")
        log = open(os.path.join(self.tmp, name + ".log"), "w+")
        env = dict(os.environ, ROSCONSOLE_STDOUT_LINE_BUFFERED="1")
        proc = subprocess.Popen([exe[0], "__ns:=/" + name, "__name:=" + name, "_backend:=cpu"] +
                                list(args), stdout=log, stderr=subprocess.STDOUT, env=env)
        self.procs.append(proc)
        rospy.wait_for_service(private + "get_stats", timeout=60)
        return proc, log

    def stop(self, proc, log):
        proc.send_signal(signal.SIGINT)
        proc.wait(20)
        log.seek(0)
        return log.read()

    def test_09_map_file_at_start_up(self):
        bt = os.path.join(self.tmp, "before_clear.bt")
        fgm = os.path.join(self.tmp, "before_clear.fgm")
        # The node advertises its services while it loads the start-up map (nodelet callbacks
        # run at once): ask until the load is in.
        proc, log = self.start_server("by_argument", [bt], {"resolution": RES})
        wait_for(lambda: self.stats("/by_argument/by_argument/").known_voxels > 0, 30,
                 "the start-up .bt loaded")
        known = self.stats("/by_argument/by_argument/").known_voxels
        self.stop(proc, log)
        self.assertGreater(known, 0)
        proc, log = self.start_server("by_parameter", [],
                                      {"resolution": RES, "map_file": fgm})
        wait_for(lambda: self.stats("/by_parameter/by_parameter/").scans > 0, 30,
                 "the start-up .fgm loaded")
        s = self.stats("/by_parameter/by_parameter/")
        self.stop(proc, log)
        self.assertEqual((s.known_voxels, s.scans), (known, 1))

    def test_10_unknown_parameters_named_in_one_warning(self):
        proc, log = self.start_server("yaml_check", [], yaml_params())
        out = self.stop(proc, log)
        self.assertNotIn("does not read", out, "an octomap_server name is unknown:\n" + out)
        proc, log = self.start_server("typo_check", [], {"sensor_model": {"hitt": 0.7},
                                                         "resolutoin": 0.1})
        out = self.stop(proc, log)
        lines = [line for line in out.splitlines() if "does not read" in line]
        self.assertEqual(len(lines), 1, out)
        self.assertIn("sensor_model/hitt (did you mean sensor_model/hit?)", lines[0])
        self.assertIn("resolutoin (did you mean resolution?)", lines[0])

    def test_11_octomap_msgs_outputs_or_the_reason(self):
        """With octomap_msgs at build time: octomap_binary / octomap_full topics and GetOctomap
        services, the binary data equal to the data of the .bt ~save_map writes; without: the
        node says why, once."""
        topics = {name for name, _ in rospy.get_published_topics()}
        proc, log = self.start_server("octomap_msgs_check")
        out = self.stop(proc, log)
        try:
            from octomap_msgs.msg import Octomap
            from octomap_msgs.srv import GetOctomap
        except ImportError:
            Octomap = None
        if Octomap is None:
            self.assertNotIn("/octomap_binary", topics)
            self.assertEqual(out.count("no octomap_binary / octomap_full"), 1, out)
            return
        self.assertNotIn("no octomap_binary", out)
        self.assertIn("/octomap_binary", topics)
        self.assertIn("/octomap_full", topics)
        # The map of the main server (loaded from before_clear.bt in test_08).
        bt = os.path.join(self.tmp, "now.bt")
        self.assertTrue(rospy.ServiceProxy(NS + "save_map", SaveMap)(bt).success)
        with open(bt, "rb") as f:
            file_data = f.read().split(b"\ndata\n", 1)[1]
        got = []
        sub = rospy.Subscriber("/octomap_binary", Octomap, got.append)
        wait_for(lambda: got, 10, "octomap_binary")
        sub.unregister()
        for msg in (got[0], rospy.ServiceProxy("/octomap_binary", GetOctomap)().map):
            self.assertTrue(msg.binary)
            self.assertEqual(msg.id, "OcTree")
            self.assertAlmostEqual(msg.resolution, RES)
            self.assertEqual(msg.header.frame_id, "map")
            self.assertEqual(bytes(b & 0xFF for b in msg.data), file_data)
        full = rospy.ServiceProxy("/octomap_full", GetOctomap)().map
        self.assertFalse(full.binary)
        self.assertEqual(full.id, "OcTree")
        self.assertGreater(len(full.data), len(file_data))
        # compress_map (true in the YAML, octomap_server's default): octomap_full is the pruned
        # full tree, the data of `fragg_map export MAP -o X.ot`; with --no-prune it is larger.
        found = find_in_workspaces(["libexec"], project="fragg_map", path="fragg_map",
                                   first_match_only=True)
        self.assertTrue(found, "the fragg_map executable is not in the workspace")
        fgm = os.path.join(self.tmp, "now.fgm")
        self.assertTrue(rospy.ServiceProxy(NS + "save_map", SaveMap)(fgm).success)
        ot_data = {}
        for name, extra in (("pruned", []), ("unpruned", ["--no-prune"])):
            ot = os.path.join(self.tmp, name + ".ot")
            subprocess.run([found[0], "export", fgm, "-o", ot] + extra, check=True,
                           stdout=subprocess.DEVNULL)
            with open(ot, "rb") as f:
                ot_data[name] = f.read().split(b"\ndata\n", 1)[1]
        self.assertEqual(bytes(b & 0xFF for b in full.data), ot_data["pruned"])
        self.assertLess(len(ot_data["pruned"]), len(ot_data["unpruned"]))

    # ---- filters, each in a server of its own fed the floor scene ----
    def test_12_filter_ground(self):
        """filter_ground with base_frame_id (base_link: the map's origin, the sensor 1 m above):
        the floor's points clear their rays and do not become obstacles, the wall does; the
        same scene without filter_ground makes the floor occupied."""
        floor, wall, _ = floor_scene()
        floor_keys = {key(x, y, z + SENSOR_Z) for x, y, z in floor}
        for on in (True, False):
            server = ExtraServer(self, "ground_" + ("on" if on else "off"), {"filter_ground": on})
            server.insert(floor + wall)
            occupied = server.occupied()
            cells = server.cells()
            server.stop()
            for x, y, z in wall:
                self.assertIn(key(x, y, z + SENSOR_Z), occupied)
            floor_occupied = floor_keys & occupied
            floor_free = [k for k, v in cells.items() if k[2] == 0 and v < 0]
            if on:
                self.assertEqual(floor_occupied, set())
                self.assertGreater(len(floor_free), 100)  # crossed by the grazing rays
            else:
                self.assertGreater(len(floor_occupied), 300)

    def test_13_filter_speckles(self):
        """filter_speckles: the lone point's cell (no occupied neighbour) is left out of
        occupied_cells / octomap_point_cloud_centers; the map keeps it; the wall stays."""
        _, wall, speckle = floor_scene()
        x, y, z = speckle[0]
        speckle_key = key(x, y, z + SENSOR_Z)
        for on in (True, False):
            server = ExtraServer(self, "speckles_" + ("on" if on else "off"),
                                 {"filter_speckles": on})
            server.insert(wall + speckle)
            occupied = server.occupied()
            centers = occupied_keys(server.last("octomap_point_cloud_centers"))
            cells = server.cells()
            server.stop()
            self.assertGreater(cells[speckle_key], 0)  # in the map either way
            self.assertEqual(len(occupied), len(wall) + (0 if on else 1))
            self.assertEqual(speckle_key in occupied, not on)
            self.assertEqual(centers, occupied)


    def test_16_cut_cell_free_as_octomap_server(self):
        """octomap_compat.launch sets sensor_model/free_cut_cell: the ray of the point beyond
        max_range (8.05 m against 5 m) frees the cell at the cut point as well, as
        octomap_server's insertScan does; a server with the liboctomap rule (false, fragg_map's
        default) leaves that cell unknown, and the cells before it are free either way."""
        _, beyond, _, _ = scene_points()
        x, y, z = beyond[0]
        r = math.sqrt(x * x + y * y + z * z)
        k = 5.0 / r  # sensor_model/max_range of the YAML
        cut = key(x * k, y * k, z * k + SENSOR_Z)
        before = key(x * k - 2 * RES, y * k, z * k + SENSOR_Z)
        path = os.path.join(self.tmp, "cut_cell.fgm")
        self.assertTrue(rospy.ServiceProxy(NS + "save_map", SaveMap)(path).success)
        in_map = cell_log_odds(path)
        self.assertLess(in_map.get(cut, 0), 0)  # free
        self.assertLess(in_map.get(before, 0), 0)
        self.assertNotIn((cut[0] + 1, cut[1], cut[2]), in_map)
        sensor_model = dict(yaml_params()["sensor_model"], free_cut_cell=False)
        server = ExtraServer(self, "cut_cell_liboctomap", {"sensor_model": sensor_model})
        server.insert(beyond + scene_points()[0])
        cells = server.cells()
        server.stop()
        self.assertNotIn(cut, cells)
        self.assertLess(cells.get(before, 0), 0)

    def test_17_dynamic_reconfigure_changes_a_parameter(self):
        """~set_parameters under octomap_server's names: the start-up values are the YAML's
        (sensor_model/max_range 5 m -> sensor_model_max_range); raising occupancy_max_z shows
        the cell above the YAML's band in occupied_cells at once; a change the node refuses
        (occupancy_min_z above occupancy_max_z) leaves the values as they were."""
        import dynamic_reconfigure.client
        server = ExtraServer(self, "reconfigure", {})
        wall, _, _, outside_band = scene_points()
        high = outside_band[0]  # map z 2.55 > occupancy_max_z 2
        high_key = key(high[0], high[1], high[2] + SENSOR_Z)
        server.insert(wall + [high])
        self.assertNotIn(high_key, server.occupied())
        client = dynamic_reconfigure.client.Client(server.private.rstrip("/"), timeout=20)
        config = client.get_configuration(timeout=20)
        self.assertAlmostEqual(config["sensor_model_max_range"], 5.0)
        self.assertAlmostEqual(config["occupancy_max_z"], 2.0)
        self.assertTrue(config["compress_map"])
        server.msgs.clear()
        config = client.update_configuration({"occupancy_max_z": 3.0})
        self.assertAlmostEqual(config["occupancy_max_z"], 3.0)
        occupied = server.occupied()
        self.assertIn(high_key, occupied)
        self.assertEqual(len(occupied), len(wall) + 1)
        config = client.update_configuration({"occupancy_min_z": 5.0})
        self.assertAlmostEqual(config["occupancy_min_z"], 0.0)
        self.assertAlmostEqual(config["occupancy_max_z"], 3.0)
        client.close()
        server.stop()

    def test_18_topics_as_octomap_server_advertises_them(self):
        """free_cells_vis_array is advertised without publish_free_space too (octomap_server
        advertises it always) and carries no marker then; octomap_compat.launch leaves
        corrected_path (fragg_map's loop-closure input) unsubscribed."""
        import rosgraph
        publishers, subscribers, _ = rosgraph.Master("/octomap_compat_test").getSystemState()
        self.assertNotIn("/octomap_server",
                         dict(subscribers).get("/corrected_path", []))
        arrays = []
        sub = rospy.Subscriber("/free_off/free_cells_vis_array", MarkerArray, arrays.append)
        server = ExtraServer(self, "free_off", {"publish_free_space": False})
        publishers, _, _ = rosgraph.Master("/octomap_compat_test").getSystemState()
        self.assertIn("/free_off/free_off",
                      dict(publishers).get("/free_off/free_cells_vis_array", []))
        server.insert(scene_points()[0])
        self.assertTrue(server.occupied())
        time.sleep(1.0)
        sub.unregister()
        server.stop()
        self.assertFalse(any(m.points for a in arrays for m in a.markers))

    # ---- colored_map and incremental_2D_projection, in servers started here ----
    def cloud_to(self, ns, points, rgb=None):
        """Publishes one cloud (sensor frame) to NS/cloud_in, with a packed rgb field if given."""
        import struct
        from sensor_msgs.msg import PointField
        # One publisher per server, kept (unregistering at once can drop the message).
        pubs = self.__class__.__dict__.get("cloud_pubs") or {}
        self.__class__.cloud_pubs = pubs
        if ns not in pubs:
            pubs[ns] = rospy.Publisher("/%s/cloud_in" % ns, PointCloud2, queue_size=5)
        pub = pubs[ns]
        wait_for(lambda: pub.get_num_connections() > 0, 20, ns + " on cloud_in")
        header = Header(frame_id="sensor", stamp=rospy.Time.now())
        if rgb is None:
            pub.publish(pc2.create_cloud_xyz32(header, points))
        else:
            packed = struct.unpack("f", struct.pack("I", rgb))[0]
            fields = [PointField("x", 0, PointField.FLOAT32, 1),
                      PointField("y", 4, PointField.FLOAT32, 1),
                      PointField("z", 8, PointField.FLOAT32, 1),
                      PointField("rgb", 12, PointField.FLOAT32, 1)]
            pub.publish(pc2.create_cloud(header, fields, [p + (packed,) for p in points]))

    def test_14_colored_map_draws_the_points_colours(self):
        """colored_map with height_map false: the occupied markers take the points' colour
        (cells without one keep `color`); with height_map true as well, height wins (as in
        octomap_server) and the node says so."""
        arrays = []
        rospy.Subscriber("/colored/occupied_cells_vis_array", MarkerArray, arrays.append,
                         queue_size=20)
        proc, log = self.start_server("colored", [], {
            "resolution": RES, "colored_map": True, "height_map": False,
            "color": {"r": 0.0, "g": 0.0, "b": 1.0, "a": 1.0},
            "sensor_model": {"max_range": 5.0}})
        wall, _, _, _ = scene_points()
        self.cloud_to("colored", wall, rgb=0x00C080)
        wait_for(lambda: self.stats("/colored/colored/").scans >= 1, 30, "the coloured cloud")
        wait_for(lambda: any(m.points for a in arrays for m in a.markers), 20, "markers")
        colours = {(round(c.r, 3), round(c.g, 3), round(c.b, 3))
                   for a in arrays for m in a.markers for c in m.colors}
        out = self.stop(proc, log)
        self.assertEqual(colours, {(0.0, round(0xC0 / 255.0, 3), round(0x80 / 255.0, 3))}, out)
        proc, log = self.start_server("both_colours", [], {"colored_map": True,
                                                           "height_map": True})
        out = self.stop(proc, log)
        self.assertIn("colored_map and height_map are both set", out)

    def test_15_incremental_2D_projection_equals_a_full_projection(self):
        """incremental_2D_projection (always on): after clouds that grow the grid and one that
        changes cells inside it, projected_map equals the projection of the same map loaded
        at start-up (built from scratch)."""
        grids = {"incremental": [], "rebuilt": []}
        for ns in grids:
            rospy.Subscriber("/%s/projected_map" % ns, OccupancyGrid, grids[ns].append)
        params = {"resolution": RES, "incremental_2D_projection": True,
                  "occupancy_min_z": 0.0, "occupancy_max_z": 2.0,
                  "sensor_model": {"max_range": 5.0}}
        proc, log = self.start_server("incremental", [], params)
        wall, _, _, _ = scene_points()
        shifted = [(x - 1.0, y + 0.6, z) for x, y, z in wall]
        for n, points in enumerate((wall, shifted, wall)):
            self.cloud_to("incremental", points)
            wait_for(lambda: self.stats("/incremental/incremental/").scans >= n + 1, 30,
                     "cloud %d" % n)
        fgm = os.path.join(self.tmp, "incremental.fgm")
        self.assertTrue(rospy.ServiceProxy("/incremental/incremental/save_map", SaveMap)(fgm)
                        .success)
        wait_for(lambda: grids["incremental"], 20, "the incremental projected_map")
        time.sleep(1.0)  # the last cloud's grid
        self.stop(proc, log)
        proc, log = self.start_server("rebuilt", [fgm], params)
        wait_for(lambda: grids["rebuilt"], 20, "the rebuilt projected_map")
        self.stop(proc, log)
        got, want = grids["incremental"][-1], grids["rebuilt"][-1]
        self.assertEqual((got.info.width, got.info.height), (want.info.width, want.info.height))
        self.assertAlmostEqual(got.info.origin.position.x, want.info.origin.position.x)
        self.assertAlmostEqual(got.info.origin.position.y, want.info.origin.position.y)
        self.assertEqual(list(got.data), list(want.data))
        self.assertIn(100, got.data)
        self.assertIn(0, got.data)

class ExtraServer:
    """A server of its own (OctomapCompatTest.start_server: namespace /NAME, node NAME) with
    the YAML's parameters and `params` over them; its outputs are recorded from the start."""
    TOPICS = ("occupied_cells", "octomap_point_cloud_centers", "projected_map",
              "occupied_cells_vis_array")

    def __init__(self, test, name, params):
        self.test = test
        self.name = name
        self.ns = "/%s/" % name
        self.private = "/%s/%s/" % (name, name)
        self.msgs = {}
        kinds = {"projected_map": OccupancyGrid, "occupied_cells_vis_array": MarkerArray}
        self.subs = [rospy.Subscriber(self.ns + t, kinds.get(t, PointCloud2),
                                      lambda m, t=t: self.msgs.__setitem__(t, m), queue_size=5)
                     for t in self.TOPICS]
        merged = yaml_params()
        merged.update(params)
        self.proc, self.log = test.start_server(name, [], merged)
        self.pub = rospy.Publisher(self.ns + "cloud_in", PointCloud2, queue_size=2)
        wait_for(lambda: self.pub.get_num_connections() > 0, 20, name + " on cloud_in")

    def stats(self):
        res = rospy.ServiceProxy(self.private + "get_stats", GetStats)()
        self.test.assertTrue(res.success, res.message)
        return res.stats

    def insert(self, points):
        """Feeds one cloud (sensor frame) and waits until it is in the map and published."""
        scans = self.stats().scans
        self.msgs.clear()
        header = Header(frame_id="sensor", stamp=rospy.Time.now())
        self.pub.publish(pc2.create_cloud_xyz32(header, points))
        wait_for(lambda: self.stats().scans > scans, 30, self.name + ": the cloud inserted")

    def last(self, topic):
        """The latest message on `topic`; for a cloud, the latest with a point (every scene
        here has occupied cells, so an empty one is from before the insertion)."""
        def ready():
            msg = self.msgs.get(topic)
            return msg is not None and (not isinstance(msg, PointCloud2) or msg.width > 0)
        wait_for(ready, 20, self.name + ": " + topic)
        return self.msgs[topic]

    def occupied(self):
        return occupied_keys(self.last("occupied_cells"))

    def cells(self):
        path = os.path.join(self.test.tmp, self.name + ".fgm")
        res = rospy.ServiceProxy(self.private + "save_map", SaveMap)(path)
        self.test.assertTrue(res.success, res.message)
        return cell_log_odds(path)

    def stop(self):
        for sub in self.subs:
            sub.unregister()
        self.pub.unregister()
        return self.test.stop(self.proc, self.log)


if __name__ == "__main__":
    rostest.rosrun("fragg_map", "octomap_compat", OctomapCompatTest)
