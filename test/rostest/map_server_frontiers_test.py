#!/usr/bin/python3
"""rostest of the map server's frontiers on the smoke bag.

test_1: nobody subscribed to frontiers / frontier_cells while the bag played, so no update
was made (MapStats.frontier_updates 0) although the map changed with every scan.
test_2: ~get_frontiers equals `fragg_map frontiers SAVED --json` on the map saved through
~save_map, with the same options (the node's frontiers/* parameters as the CLI's cli_views and
cli_sensor): frontier cell count, every cluster's id, cells, centroid,
bounds and direction, and its viewpoints (position, yaw, gain, and with a robot position the
distance and gain per metre) within float tolerance; with the parameters' defaults, with a
box, a robot position, the LiDAR sensor and a larger min_cluster, and with the robot given as
the tf frame base_link (its latest pose: the last scan's).
test_3: bad requests (k 0 or negative, a NaN or inverted box, an unknown sensor or frame, ...)
answer success=false with the reason and leave the map as it was.
test_4: subscribed, the topics arrive: the cloud holds the service's frontier cells, the
markers the service's clusters (one CUBE_LIST each, the same cells; an even subsample of both
beyond frontiers/max_marker_cells) and arrows at the service's viewpoints (k =
frontiers/viewpoints); a sector of a scan inserted again updates them incrementally (fewer
blocks examined than the map holds) to the service's new answer.
test_5: unsubscribed again, a map change makes no update."""
import json
import math
import os
import re
import shutil
import subprocess
import tempfile
import time
import unittest

import rosbag
import rospy
import rostest
from catkin.find_in_workspaces import find_in_workspaces
from geometry_msgs.msg import Point
from sensor_msgs import point_cloud2
from sensor_msgs.msg import PointCloud2
from visualization_msgs.msg import Marker, MarkerArray

from fragg_map.srv import ClearBox, GetFrontiers, GetFrontiersRequest, GetStats, SaveMap
from map_server_checks import NS, wait_for
from map_server_correction_test import read_bag

TOL = 1e-6


def yaw_of(q):
    return math.atan2(2.0 * (q.w * q.z + q.x * q.y), 1.0 - 2.0 * (q.y * q.y + q.z * q.z))


def angle_diff(a, b):
    return abs(math.atan2(math.sin(a - b), math.cos(a - b)))


def xyz(p):
    return [p.x, p.y, p.z]


class MapServerFrontiersTest(unittest.TestCase):
    @classmethod
    def setUpClass(cls):
        rospy.init_node("map_server_frontiers_test")
        for name in ("get_stats", "save_map", "get_frontiers", "clear_bbox"):
            rospy.wait_for_service(NS + name, timeout=60)
        cls.get_stats = rospy.ServiceProxy(NS + "get_stats", GetStats)
        cls.save = rospy.ServiceProxy(NS + "save_map", SaveMap)
        cls.get_frontiers = rospy.ServiceProxy(NS + "get_frontiers", GetFrontiers)
        cls.clear = rospy.ServiceProxy(NS + "clear_bbox", ClearBox)
        cls.tmp = tempfile.mkdtemp(prefix="fragg_map_frontiers_")
        found = find_in_workspaces(["libexec"], project="fragg_map", path="fragg_map",
                                   first_match_only=True)
        assert found, "the fragg_map executable is not in the workspace"
        cls.cli = found[0]
        cls.scans = rospy.get_param("~scans")
        wait_for(lambda: cls.get_stats().stats.scans >= cls.scans, 150, "every scan inserted")
        cls.after_bag = cls.get_stats().stats
        stamps, base, _, _ = read_bag(rospy.get_param("~bag"), rospy.get_param("~topic"))
        cls.last_base_position = base[-1][0]
        with rosbag.Bag(rospy.get_param("~bag")) as bag:
            clouds = [m for _, m, _ in bag.read_messages(topics=[rospy.get_param("~topic")])]
        cls.last_cloud = clouds[-1]
        cls.arrays, cls.clouds = [], []
        cls.subs = []

    @classmethod
    def tearDownClass(cls):
        shutil.rmtree(cls.tmp, ignore_errors=True)

    def stats(self):
        res = self.get_stats()
        self.assertTrue(res.success, res.message)
        return res.stats

    def saved(self, name):
        path = os.path.join(self.tmp, name)
        res = self.save(path)
        self.assertTrue(res.success, res.message)
        return path

    def cli_frontiers(self, map_path, *options):
        out = subprocess.run([self.cli, "frontiers", map_path, "--json"] + list(options),
                             check=True, stdout=subprocess.PIPE).stdout
        return json.loads(out)

    def call(self, **kw):
        req = GetFrontiersRequest(**kw)
        return self.get_frontiers(req)

    def assert_same(self, res, cli, what, robot=False):
        self.assertTrue(res.success, "%s: %s" % (what, res.message))
        self.assertEqual(res.frontier_cells, cli["frontier_cells"], what)
        self.assertEqual(len(res.clusters), len(cli["clusters"]), what)
        for c, j in zip(res.clusters, cli["clusters"]):
            self.assertEqual(c.id, j["id"], what)
            self.assertEqual(c.cells, j["cells"], what)
            for got, want in [(xyz(c.centroid), j["centroid"]), (xyz(c.min), j["min"]),
                              (xyz(c.max), j["max"]), (xyz(c.direction), j["direction"])]:
                for a, b in zip(got, want):
                    self.assertAlmostEqual(a, b, delta=TOL, msg=what)
            self.assertEqual(len(c.viewpoints), len(j["viewpoints"]), "%s: cluster %d" %
                             (what, c.id))
            self.assertEqual(len(c.gains_bits), len(c.viewpoints))
            for i, v in enumerate(j["viewpoints"]):
                for a, b in zip(xyz(c.viewpoints[i].position), v["position"]):
                    self.assertAlmostEqual(a, b, delta=TOL, msg=what)
                q = c.viewpoints[i].orientation
                self.assertAlmostEqual(q.x, 0.0, delta=TOL)
                self.assertAlmostEqual(q.y, 0.0, delta=TOL)
                self.assertLess(angle_diff(yaw_of(q), v["yaw"]), TOL, what)
                self.assertAlmostEqual(c.gains_bits[i], v["gain_bits"],
                                       delta=TOL * max(1.0, v["gain_bits"]), msg=what)
                if robot:
                    self.assertAlmostEqual(c.distances_m[i], v["distance"], delta=TOL, msg=what)
                    self.assertAlmostEqual(c.scores[i], v["gain_per_metre"],
                                           delta=TOL * max(1.0, v["gain_per_metre"]), msg=what)

    # --- no subscribers during the bag -------------------------------------------------------
    def test_1_no_updates_without_subscribers(self):
        self.assertEqual(self.after_bag.scans, self.scans)
        self.assertGreater(self.after_bag.known_voxels, 0)
        self.assertEqual(self.after_bag.frontier_updates, 0,
                         "frontier topics updated while nobody subscribed")

    # --- ~get_frontiers against the CLI --------------------------------------------------------
    def test_2_service_agrees_with_the_cli(self):
        map_path = self.saved("frontiers.fgm")
        queries = self.stats().frontier_queries

        views = rospy.get_param("~cli_views").split()
        # The defaults: a LiDAR map, so a coarse grid sized from the beam spacing and the
        # coverage gain (the message says which); the CLI given the same grid and gain.
        res = self.call(k=2)
        self.assertTrue(res.success, res.message)
        grid = re.search(r"coarse cells of ([0-9.]+) m, from beams", res.message)
        self.assertIsNotNone(grid, "a LiDAR map gets a coarse grid: " + res.message)
        coarse = int(round(float(grid.group(1)) / rospy.get_param("/fragg_map/resolution", 0.05)))
        self.assertIn(coarse, (2, 4, 8), res.message)
        self.assertIn("viewpoint gain coverage", res.message)
        cli = self.cli_frontiers(map_path, "--viewpoints", "2", *views, "--coarse-cells",
                                 str(coarse), "--gain", "coverage",
                                 *rospy.get_param("~cli_sensor").split())
        self.assert_same(res, cli, "defaults (coarse %d, coverage)" % coarse)
        self.assertGreater(res.frontier_cells, 100)
        self.assertTrue(any(c.viewpoints for c in res.clusters), "no viewpoint at all")
        # The map's own cells and the entropy gain, asked in the request.
        res = self.call(k=2, coarse_cells=1, gain="entropy")
        cli = self.cli_frontiers(map_path, "--viewpoints", "2", *views,
                                 *rospy.get_param("~cli_sensor").split())
        self.assert_same(res, cli, "map cells")
        rospy.loginfo("defaults: %d frontier cells, %d clusters, %.1f ms (CLI %.1f + %.1f ms)",
                      res.frontier_cells, len(res.clusters), res.ms, cli["ms_cells"],
                      cli["ms_clusters_viewpoints"])
        self.assertGreater(res.frontier_cells, 1000)
        self.assertGreater(len(res.clusters), 3)
        self.assertTrue(any(c.viewpoints for c in res.clusters), "no viewpoint at all")

        # A box around the robot, its position, the LiDAR sensor and larger clusters.
        robot = Point(*self.last_base_position)
        box_min = Point(robot.x - 15.0, robot.y - 15.0, robot.z - 5.0)
        box_max = Point(robot.x + 15.0, robot.y + 15.0, robot.z + 10.0)
        res = self.call(k=3, min_cluster=20, use_box=True, box_min=box_min, box_max=box_max,
                        use_robot_position=True, robot_position=robot, sensor="lidar",
                        rays=[90, 8], max_range=8.0, coarse_cells=1)
        cli = self.cli_frontiers(map_path, *views, "--viewpoints", "3", "--min-cluster", "20",
                                 "--box",
                                 *[repr(v) for v in xyz(box_min) + xyz(box_max)], "--robot",
                                 *[repr(v) for v in xyz(robot)], "--sensor", "lidar", "--rays",
                                 "90", "8", "--max-range", "8")
        self.assert_same(res, cli, "box, robot, lidar", robot=True)
        self.assertGreater(len(res.clusters), 0)
        for c in res.clusters:
            self.assertGreaterEqual(c.cells, 20)

        # The robot as a tf frame: base_link's latest pose (the last scan's).
        res_tf = self.call(k=3, min_cluster=20, use_box=True, box_min=box_min, box_max=box_max,
                           robot_frame="base_link", sensor="lidar", rays=[90, 8], max_range=8.0,
                           coarse_cells=1)
        self.assert_same(res_tf, cli, "robot frame base_link", robot=True)

        # The box on a coarse grid (only the box's part of the map copied): as the CLI.
        res = self.call(k=3, min_cluster=4, use_box=True, box_min=box_min, box_max=box_max,
                        coarse_cells=2, gain="coverage")
        cli = self.cli_frontiers(map_path, *views, "--viewpoints", "3", "--min-cluster", "4",
                                 "--box", *[repr(v) for v in xyz(box_min) + xyz(box_max)],
                                 "--coarse-cells", "2", "--gain", "coverage",
                                 *rospy.get_param("~cli_sensor").split())
        self.assert_same(res, cli, "box on a coarse grid")
        self.assertGreater(len(res.clusters), 0)
        self.assertEqual(self.stats().frontier_queries, queries + 5)

    # --- bad requests ----------------------------------------------------------------------
    def test_3_bad_requests_are_refused(self):
        before = self.stats()
        nan = float("nan")
        for kw, why, says in [
            (dict(k=0), "k 0", "k"),
            (dict(k=-2), "k negative", "k"),
            (dict(k=1, min_cluster=-1), "min_cluster negative", "min_cluster"),
            (dict(k=1, use_box=True, box_min=Point(nan, 0, 0), box_max=Point(1, 1, 1)),
             "a NaN box", "box"),
            (dict(k=1, use_box=True, box_min=Point(1, 0, 0), box_max=Point(0, 1, 1)),
             "an inverted box", "box"),
            (dict(k=1, sensor="sonar"), "an unknown sensor", "sonar"),
            (dict(k=1, rays=[10]), "one rays value", "rays"),
            (dict(k=1, rays=[0, 4]), "zero rays", "sensor"),
            (dict(k=1, fov=[4.0, 1.0]), "a field of view beyond pi", "sensor"),
            (dict(k=1, max_range=-1.0), "a negative range", "max_range"),
            (dict(k=1, robot_frame="nowhere"), "an unknown frame", "nowhere"),
            (dict(k=1, coarse_cells=3), "a coarse edge of 3 cells", "coarse_cells"),
            (dict(k=1, coarse_cells=-1), "a negative coarse edge", "coarse_cells"),
            (dict(k=1, gain="bits"), "an unknown gain", "gain"),
            (dict(k=1, robot_frame="base_link", use_robot_position=True), "position and frame",
             "not both"),
            (dict(k=1, use_robot_position=True, robot_position=Point(nan, 0, 0)),
             "a NaN robot position", "robot"),
        ]:
            res = self.call(**kw)
            self.assertFalse(res.success, why)
            self.assertIn(says, res.message, why)
            self.assertEqual(len(res.clusters), 0, why)
            self.assertEqual(res.frontier_cells, 0, why)
        after = self.stats()
        self.assertEqual(after.known_voxels, before.known_voxels)
        self.assertEqual(after.scans, before.scans)
        self.assertEqual(after.frontier_queries, before.frontier_queries)

    # --- topics ----------------------------------------------------------------------------
    def cloud_points(self, msg):
        return sorted(tuple(round(v, 4) for v in p)
                      for p in point_cloud2.read_points(msg, ("x", "y", "z")))

    def check_topics_against_service(self, arrays_from, clouds_from, what):
        """Waits for the messages published after the given counts and compares them with a
        ~get_frontiers answer (k = frontiers/viewpoints) made now."""
        wait_for(lambda: len(self.arrays) > arrays_from and len(self.clouds) > clouds_from, 90,
                 "frontier topics (%s)" % what)
        k = rospy.get_param(NS + "frontiers/viewpoints")
        cap = rospy.get_param(NS + "frontiers/max_marker_cells")
        res = self.call(k=k, coarse_cells=1)  # the topics are on the map's own cells
        self.assertTrue(res.success, res.message)
        cloud = self.clouds[-1]
        n = res.frontier_cells
        stride = 1 if n <= cap else -(-n // cap)
        self.assertEqual(cloud.header.frame_id, "map")
        self.assertEqual(cloud.width, len(range(0, n, stride)), what)
        array = self.arrays[-1]
        self.assertEqual(array.markers[0].action, Marker.DELETEALL)
        cubes = [m for m in array.markers if m.ns == "frontier_cells"]
        arrows = [m for m in array.markers if m.ns == "viewpoints"]
        for m in cubes:
            self.assertEqual(m.type, Marker.CUBE_LIST)
        for m in arrows:
            self.assertEqual(m.type, Marker.ARROW)
        clustered = sum(c.cells for c in res.clusters)
        stride_c = 1 if clustered <= cap else -(-clustered // cap)
        self.assertEqual(sum(len(m.points) for m in cubes), len(range(0, clustered, stride_c)),
                         what)
        if n <= cap:
            # One CUBE_LIST per cluster with its cells; every clustered cell is in the cloud.
            self.assertEqual(sorted(len(m.points) for m in cubes),
                             sorted(c.cells for c in res.clusters), what)
            in_cloud = set(self.cloud_points(cloud))
            for m in cubes:
                for p in m.points:
                    self.assertIn((round(p.x, 4), round(p.y, 4), round(p.z, 4)), in_cloud)
        want = sorted(tuple(round(v, 5) for v in xyz(p.position)) + (round(yaw_of(p.orientation), 5),)
                      for c in res.clusters for p in c.viewpoints)
        got = sorted(tuple(round(v, 5) for v in xyz(m.pose.position)) +
                     (round(yaw_of(m.pose.orientation), 5),) for m in arrows)
        self.assertEqual(got, want, what)
        return res

    def test_4_topics_while_subscribed(self):
        before = self.stats().frontier_updates
        self.subs.append(rospy.Subscriber("/frontiers", MarkerArray, self.arrays.append,
                                          queue_size=10))
        self.subs.append(rospy.Subscriber("/frontier_cells", PointCloud2, self.clouds.append,
                                          queue_size=10))
        res = self.check_topics_against_service(0, 0, "first subscription")
        s = self.stats()
        self.assertGreater(s.frontier_updates, before)
        self.assertEqual(s.frontier_cells, res.frontier_cells)
        # The same map: no more updates while nothing changes.
        updates = s.frontier_updates
        time.sleep(1.5)
        self.assertEqual(self.stats().frontier_updates, updates)

        # A 30-degree sector of the last scan inserted again (its transform is the latest tf
        # holds): an incremental update, only the blocks it changed and their neighbours
        # examined, fewer than the map holds.
        pub = rospy.Publisher(rospy.get_param("~topic"), PointCloud2, queue_size=1)
        wait_for(lambda: pub.get_num_connections() > 0, 10, "the node subscribing the clouds")
        scans = self.stats().scans
        arrays, clouds = len(self.arrays), len(self.clouds)
        sector = [p for p in point_cloud2.read_points(self.last_cloud, ("x", "y", "z"),
                                                       skip_nans=True)
                  if 0.0 < math.atan2(p[1], p[0]) < math.radians(30.0)]
        self.assertGreater(len(sector), 10)
        pub.publish(point_cloud2.create_cloud_xyz32(self.last_cloud.header, sector))
        wait_for(lambda: self.stats().scans == scans + 1, 30, "the scan inserted again")
        wait_for(lambda: self.stats().frontier_updates > updates, 90, "an incremental update")
        s = self.stats()
        self.assertFalse(s.frontier_update_full, "an insertion updates incrementally")
        self.assertGreater(s.frontier_blocks_examined, 0)
        self.assertLess(s.frontier_blocks_examined, s.blocks)
        rospy.loginfo("incremental frontier update: %d of %d blocks examined, %d cells, %.1f ms",
                      s.frontier_blocks_examined, s.blocks, s.frontier_cells, s.frontier_ms_last)
        res = self.check_topics_against_service(arrays, clouds, "after the insertion")
        self.assertEqual(s.frontier_cells, res.frontier_cells)
        pub.unregister()

    def test_5_no_updates_after_unsubscribing(self):
        for sub in self.subs:
            sub.unregister()
        del self.subs[:]
        time.sleep(1.0)  # the node sees the connections close
        updates = self.stats().frontier_updates
        known = self.stats().known_voxels
        c = self.last_base_position
        res = self.clear(min=Point(c[0] - 2.0, c[1] - 2.0, c[2] - 2.0),
                         max=Point(c[0] + 2.0, c[1] + 2.0, c[2] + 2.0))
        self.assertTrue(res.success, res.message)
        self.assertLess(self.stats().known_voxels, known, "the map changed")
        time.sleep(2.0)  # 8 periods at frontiers/rate_hz 4
        self.assertEqual(self.stats().frontier_updates, updates,
                         "frontier topics updated with nobody subscribed")


if __name__ == "__main__":
    rostest.rosrun("fragg_map", "map_server_frontiers", MapServerFrontiersTest)
