"""Checks every map-server rostest runs on its bag: every placeable scan inserted (none
dropped from the queue, the expected number dropped for lack of tf), incremental markers, and
the map saved through ~save_map equal, cell for cell, to `fragg_map build` on the same bag.
Parameters (private): bag, topic, frame, scans, no_tf, cli_args (options given to every
`fragg_map build`, matching the node's parameters). The fragg_map executable is found
in the workspace; files go to a temporary folder."""
import json
import os
import shutil
import struct
import subprocess
import tempfile
import time
import unittest

from catkin.find_in_workspaces import find_in_workspaces

import rospy
from sensor_msgs.msg import PointCloud2, PointField
from visualization_msgs.msg import Marker, MarkerArray

from fragg_map.srv import GetStats, SaveMap

NS = "/fragg_map/"


def map_cloud(points):
    """An unorganised float32 x, y, z cloud in the map frame, stamped now, from (x, y, z)s."""
    msg = PointCloud2()
    msg.header.frame_id = "map"
    msg.header.stamp = rospy.Time.now()
    msg.fields = [PointField(name=n, offset=4 * k, datatype=PointField.FLOAT32, count=1)
                  for k, n in enumerate("xyz")]
    msg.point_step = 12
    msg.width = len(points)
    msg.height = 1
    msg.row_step = 12 * len(points)
    msg.is_bigendian = False
    msg.is_dense = True
    msg.data = b"".join(struct.pack("<3f", *p) for p in points)
    return msg


def wait_for(predicate, timeout_s, what):
    deadline = time.monotonic() + timeout_s  # wall clock: sim time stops with the bag
    while time.monotonic() < deadline:
        if predicate():
            return
        time.sleep(0.1)
    raise AssertionError("timed out waiting for " + what)


class MapServerBagChecks(unittest.TestCase):
    @classmethod
    def setUpClass(cls):
        rospy.init_node("map_server_test")
        cls.arrays = []
        rospy.Subscriber("/occupied_cells_vis_array", MarkerArray, cls.arrays.append,
                         queue_size=100)
        for name in ("get_stats", "save_map"):
            rospy.wait_for_service(NS + name, timeout=60)
        cls.get_stats = rospy.ServiceProxy(NS + "get_stats", GetStats)
        cls.save = rospy.ServiceProxy(NS + "save_map", SaveMap)
        cls.tmp = tempfile.mkdtemp(prefix="fragg_map_rostest_")
        found = find_in_workspaces(["libexec"], project="fragg_map", path="fragg_map",
                                   first_match_only=True)
        assert found, "the fragg_map executable is not in the workspace"
        cls.cli = found[0]
        cls.scans = rospy.get_param("~scans")
        cls.no_tf = rospy.get_param("~no_tf", 0)
        wait_for(lambda: cls.get_stats().stats.scans >= cls.scans and
                 cls.get_stats().stats.dropped_no_tf >= cls.no_tf, 120,
                 "every scan inserted or dropped")
        cls.after_bag = cls.get_stats().stats

    @classmethod
    def tearDownClass(cls):
        shutil.rmtree(cls.tmp, ignore_errors=True)

    def stats(self):
        res = self.get_stats()
        self.assertTrue(res.success, res.message)
        return res.stats

    def test_1_every_scan_inserted(self):
        s = self.after_bag
        self.assertEqual(s.scans, self.scans)
        self.assertEqual(s.dropped_queue_full, 0)
        self.assertEqual(s.rejected_clouds, 0)
        self.assertEqual(s.dropped_no_tf, self.no_tf)
        self.assertGreater(s.known_voxels, 0)
        self.assertGreater(s.insertion_ms_mean, 0.0)

    def test_2_markers_are_incremental(self):
        wait_for(lambda: len(self.arrays) >= 2, 10, "marker arrays")
        # A full republish (DELETEALL first) at start-up or, latched, for this late subscriber.
        self.assertTrue(any(m.action == Marker.DELETEALL for a in self.arrays for m in a.markers),
                        "no full republish")
        shown = {}
        for a in self.arrays:
            for m in a.markers:
                if m.action == Marker.DELETEALL:
                    shown.clear()
                elif m.action == Marker.DELETE:
                    shown.pop(m.id, None)
                else:
                    self.assertEqual(m.type, Marker.CUBE_LIST)
                    self.assertEqual(m.ns, "occupied")
                    self.assertEqual(len(m.points), len(m.colors))
                    shown[m.id] = len(m.points)
        later = [a for a in self.arrays[1:]
                 if not any(m.action == Marker.DELETEALL for m in a.markers)]
        self.assertTrue(later, "no incremental array")
        # An increment carries only the blocks whose occupied cells changed.
        self.assertLess(min(len(a.markers) for a in later), len(shown))
        self.assertGreater(sum(shown.values()), 0)

    def cli_build(self, source, out, *options):
        """`fragg_map build source -o out` with the CPU backend and the test's cli_args. The
        node keeps its scans (keep_scans, default true) as float32 points as received
        (scan_store/point_step 0, the default), which leaves its map the map of the received
        clouds: the build is then a plain one with the CLI's defaults. Only a node that
        quantises kept points (point_step > 0) integrates the quantised points; the build then
        keeps its scans at the same step."""
        keep = []
        step = float(rospy.get_param(NS + "scan_store/point_step", 0.0))
        if rospy.get_param(NS + "keep_scans", True) and step > 0.0:
            keep = ["--keep-scans", "--scan-step", repr(step)]
        cli_args = rospy.get_param("~cli_args", "").split()
        # The node's max_range (the server's default is 100 m, the CLI's none) unless the
        # test gives its own.
        if "--max-range" not in cli_args + list(options) and rospy.has_param(NS + "sensor_model/max_range"):
            keep += ["--max-range", repr(float(rospy.get_param(NS + "sensor_model/max_range")))]
        subprocess.run([self.cli, "build", source, "-o", out, "--backend", "cpu"] + keep +
                       cli_args + list(options),
                       check=True, stdout=subprocess.DEVNULL, stderr=subprocess.DEVNULL)

    def compare(self, a, b):
        out = subprocess.run([self.cli, "compare", a, b, "--json"], check=True,
                             stdout=subprocess.PIPE).stdout
        return json.loads(out)

    def node_map(self):
        path = os.path.join(self.tmp, "node.fgm")
        if not os.path.exists(path):
            res = self.save(path)
            self.assertTrue(res.success, res.message)
        return path

    def test_3_saved_map_equals_cli_build(self):
        ref = os.path.join(self.tmp, "cli.fgm")
        self.cli_build(rospy.get_param("~bag"), ref, "--topic", rospy.get_param("~topic"),
                       "--frame", rospy.get_param("~frame", "map"))
        cmp = self.compare(ref, self.node_map())
        self.assertEqual(cmp["known_in_a"], cmp["known_in_b"])
        self.assertEqual(cmp["agreeing"], cmp["known_in_either"], cmp)
