#!/usr/bin/python3
"""rostest: service calls while a long insertion runs (issue 18). Clouds in the map frame
(sensor at the origin, no tf): A, a sparse shell 4 m around; B, 600,000 points on a 2 x 2 m
patch 20 m ahead (+x): hundreds of thousands of 200-cell rays, seconds of insertion on a small
machine and few blocks; C, the same patch 20 m to the left (+y, x > 0 only). While B is inserted
two threads call ~get_stats and ~save_map over and over; while C is inserted one calls
~clear_bbox on a box at x < 0 that A observed and C's rays never enter. Checks:
  - every call answers success (after the insertion, whose write lock they wait for), and for
    each service a call waited for at least half of the insertion (it overlapped it);
  - every map ~save_map wrote meanwhile is the map before B (1 scan) or after B (2 scans),
    block for block: never a half-inserted cloud;
  - after C: the blocks inside the box are gone, the blocks away from it equal
    `fragg_map build` of A, B, C; the node answers, holds 3 scans and dropped no cloud."""
import array
import math
import os
import random
import shutil
import struct
import subprocess
import tempfile
import threading
import time
import unittest

import rosbag
import rospy
import rostest
from catkin.find_in_workspaces import find_in_workspaces
from geometry_msgs.msg import Point
from sensor_msgs.msg import PointCloud2, PointField

from fgm_cells import BLOCK_EDGE, read_blocks
from map_server_checks import wait_for
from fragg_map.srv import ClearBox, GetStats, SaveMap

NS = "/fragg_map/"
TOPIC = "/busy_points"
BIG_POINTS = 600000
BOX_MIN = (-4.8, -1.6, -1.6)  # block-aligned at 5 or 10 cm; A's shell passes through it
BOX_MAX = (-2.4, 1.6, 1.6)


def cloud(points_xyz, stamp):
    """An unorganised float32 x, y, z cloud in the map frame from a flat list x0 y0 z0 x1..."""
    msg = PointCloud2()
    msg.header.frame_id = "map"
    msg.header.stamp = stamp
    msg.fields = [PointField(name=n, offset=4 * k, datatype=PointField.FLOAT32, count=1)
                  for k, n in enumerate("xyz")]
    msg.point_step = 12
    msg.width = len(points_xyz) // 3
    msg.height = 1
    msg.row_step = 12 * msg.width
    msg.is_bigendian = False
    msg.is_dense = True
    msg.data = array.array("f", points_xyz).tobytes()
    return msg


def shell(radius, n):
    """n points on a sphere (a Fibonacci lattice)."""
    pts = []
    golden = math.pi * (3.0 - math.sqrt(5.0))
    for i in range(n):
        z = 1.0 - 2.0 * (i + 0.5) / n
        r = math.sqrt(1.0 - z * z)
        pts += [radius * r * math.cos(golden * i), radius * r * math.sin(golden * i), radius * z]
    return pts


def patch(axis, n, seed):
    """n points on a 2 x 2 m patch 20 m along +x (axis 0) or +y (axis 1, at x in [1, 3])."""
    rng = random.Random(seed)
    pts = []
    for _ in range(n):
        u, v = rng.uniform(-1.0, 1.0), rng.uniform(-1.0, 1.0)
        pts += [20.0, u, v] if axis == 0 else [2.0 + u, 20.0, v]
    return pts


def scans_in(path):
    with open(path, "rb") as f:
        return struct.unpack_from("<Q", f.read(88), 80)[0]


def block_range(lo, hi, resolution):
    """Block keys whose cells lie inside [lo, hi) on every axis (hi block-aligned)."""
    edge = resolution * BLOCK_EDGE
    return [range(int(round(lo[a] / edge)), int(round(hi[a] / edge))) for a in range(3)]


class Caller(threading.Thread):
    """Calls `fn` over and over until stopped: (start, end, success, message, extra) each."""

    def __init__(self, fn, pause_s):
        super().__init__(daemon=True)
        self.fn = fn
        self.pause_s = pause_s
        self.calls = []
        self.stop = threading.Event()

    def run(self):
        k = 0
        while not self.stop.is_set():
            t = time.monotonic()
            try:
                ok, msg, extra = self.fn(k)
            except (rospy.ServiceException, rospy.ROSException) as e:
                ok, msg, extra = False, str(e), None
            self.calls.append((t, time.monotonic(), ok, msg, extra))
            k += 1
            time.sleep(self.pause_s)

    def finish(self):
        self.stop.set()
        self.join(timeout=120)

    def longest(self):
        return max(end - start for start, end, _, _, _ in self.calls)


class BusyServices(unittest.TestCase):
    @classmethod
    def setUpClass(cls):
        rospy.init_node("map_server_busy_test")
        cls.tmp = tempfile.mkdtemp(prefix="fragg_map_busy_", dir="/tmp")
        found = find_in_workspaces(["libexec"], project="fragg_map", path="fragg_map",
                                   first_match_only=True)
        assert found, "the fragg_map executable is not in the workspace"
        cls.cli = found[0]
        for name in ("get_stats", "save_map", "clear_bbox"):
            rospy.wait_for_service(NS + name, timeout=120)
        cls.pub = rospy.Publisher(TOPIC, PointCloud2, queue_size=5)
        wait_for(lambda: cls.pub.get_num_connections() > 0, 60, "the node to subscribe")

    @classmethod
    def tearDownClass(cls):
        shutil.rmtree(cls.tmp, ignore_errors=True)

    def proxy(self, name, srv):
        return rospy.ServiceProxy(NS + name, srv, persistent=True)

    def stats(self):
        res = self.proxy("get_stats", GetStats)()
        self.assertTrue(res.success, res.message)
        return res.stats

    def save(self, name):
        path = os.path.join(self.tmp, name)
        res = self.proxy("save_map", SaveMap)(path)
        self.assertTrue(res.success, res.message)
        return path

    def insert_while(self, msg, scans_after, callers):
        """Publishes `msg` with the callers running; stops them once it is inserted. The
        insertion's duration [s] from ~stats."""
        for c in callers:
            c.start()
        time.sleep(0.2)  # a few calls on the idle map first
        self.pub.publish(msg)
        # (~get_stats, not the ~stats topic: its 1-deep publisher queue may replace the
        # insertion's message by the one a ~clear_bbox publishes right after it.)
        wait_for(lambda: self.stats().scans >= scans_after, 240, "the big cloud's insertion")
        time.sleep(0.3)  # the calls that waited for it answer
        for c in callers:
            c.finish()
        got = self.stats()
        self.assertEqual(got.scans, scans_after)
        return got.insertion_ms_last / 1000.0

    def expect_answered_and_overlapped(self, caller, name, insertion_s):
        self.assertTrue(caller.calls, name + ": no call made")
        failed = [c for c in caller.calls if not c[2]]
        self.assertFalse(failed, "%s failed during the insertion: %s" % (name, failed[:3]))
        rospy.loginfo("busy test: %s: %d calls during a %.2f s insertion, longest %.2f s",
                      name, len(caller.calls), insertion_s, caller.longest())
        self.assertGreaterEqual(caller.longest(), 0.5 * insertion_s,
                                name + ": no call overlapped the insertion")

    def test_calls_during_long_insertions(self):
        t0 = rospy.Time.now()
        a = cloud(shell(4.0, 4000), t0)
        self.pub.publish(a)
        wait_for(lambda: self.stats().scans == 1, 120, "cloud A")
        before = read_blocks(self.save("before.fgm"))[0]
        self.assertTrue(before)

        # B with ~get_stats and ~save_map running.
        stats_proxy = self.proxy("get_stats", GetStats)
        save_proxy = self.proxy("save_map", SaveMap)

        def call_stats(k):
            res = stats_proxy()
            return res.success, res.message, res.stats.scans

        def call_save(k):
            path = os.path.join(self.tmp, "during_%03d.fgm" % k)
            res = save_proxy(path)
            return res.success, res.message, path

        stats_caller, save_caller = Caller(call_stats, 0.02), Caller(call_save, 0.1)
        b = cloud(patch(0, BIG_POINTS, 1), t0 + rospy.Duration(1))
        insertion_b = self.insert_while(b, 2, [stats_caller, save_caller])
        self.expect_answered_and_overlapped(stats_caller, "get_stats", insertion_b)
        self.expect_answered_and_overlapped(save_caller, "save_map", insertion_b)
        after = read_blocks(self.save("after_b.fgm"))[0]
        self.assertNotEqual(after, before)
        counts = {1: 0, 2: 0}
        for _, _, _, _, path in save_caller.calls:
            n = scans_in(path)
            self.assertIn(n, (1, 2), path)
            self.assertEqual(read_blocks(path)[0], before if n == 1 else after,
                             "%s (%d scans) is not the map before or after the cloud" %
                             (path, n))
            counts[n] += 1
        self.assertTrue(all(s in (1, 2) for _, _, _, _, s in stats_caller.calls))
        rospy.loginfo("busy test: maps saved during B: %d before it, %d after it",
                      counts[1], counts[2])

        # C with ~clear_bbox running.
        clear_proxy = self.proxy("clear_bbox", ClearBox)

        def call_clear(k):
            res = clear_proxy(Point(*BOX_MIN), Point(*BOX_MAX))
            return res.success, res.message, None

        clear_caller = Caller(call_clear, 0.05)
        c = cloud(patch(1, BIG_POINTS, 2), t0 + rospy.Duration(2))
        insertion_c = self.insert_while(c, 3, [clear_caller])
        self.expect_answered_and_overlapped(clear_caller, "clear_bbox", insertion_c)

        final = self.stats()
        self.assertEqual(final.scans, 3)
        self.assertEqual(final.dropped_clouds, 0)
        mine, resolution = read_blocks(self.save("final.fgm"))
        bag = os.path.join(self.tmp, "abc.bag")
        with rosbag.Bag(bag, "w") as out:
            for msg in (a, b, c):
                out.write(TOPIC, msg, msg.header.stamp)
        built = os.path.join(self.tmp, "built.fgm")
        subprocess.run([self.cli, "build", bag, "-o", built, "--topic", TOPIC, "--frame", "map"],
                       check=True, stdout=subprocess.DEVNULL)
        theirs = read_blocks(built)[0]
        inside = block_range(BOX_MIN, BOX_MAX, resolution)
        edge = resolution * BLOCK_EDGE
        near = block_range([v - edge for v in BOX_MIN], [v + edge for v in BOX_MAX], resolution)

        def within(key, ranges):
            return all(key[i] in ranges[i] for i in range(3))

        self.assertTrue(any(within(k, inside) for k in theirs), "A did not reach the box")
        self.assertFalse([k for k in mine if within(k, inside)], "blocks left in the box")
        away_mine = {k: v for k, v in mine.items() if not within(k, near)}
        away_theirs = {k: v for k, v in theirs.items() if not within(k, near)}
        self.assertTrue(away_theirs)
        self.assertEqual(away_mine, away_theirs,
                         "the map away from the box differs from `fragg_map build`")


if __name__ == "__main__":
    rostest.rosrun("fragg_map", "map_server_busy", BusyServices)
