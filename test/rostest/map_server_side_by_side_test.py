#!/usr/bin/python3
"""rostest: services side by side (issue 35, item 4). Clouds in the map frame (sensor at the
origin, no tf): a sphere of 6 m with holes (frontiers through them and around it). A long
~get_frontiers (LiDAR gain sensor; its rays scaled until one call takes >= 3 s here) runs in
a thread; meanwhile the test publishes small clouds and calls ~get_stats and ~save_map.
Checks (orders and counts, not timings):
  - the long call answers success, and its answer belongs to the map before the clouds sent
    while it ran (its revision is older than the map's afterwards);
  - ~get_stats and ~save_map calls started while it ran returned before it did (a service of
    its own thread: not queued behind it);
  - a ~get_stats answer returned before the long call did counts more scans than the map held
    when it started (insertion not held back by the query's read of the map);
  - every cloud sent is inserted, none dropped, and the counters sum to the clouds received."""
import math
import os
import random
import shutil
import tempfile
import threading
import time
import unittest

import rospy
import rostest
from sensor_msgs.msg import PointCloud2

from map_server_checks import NS, map_cloud, wait_for
from fragg_map.srv import GetFrontiers, GetFrontiersRequest, GetStats, SaveMap

TOPIC = "/side_points"
LONG_S = 3.0  # the long call lasts at least this long (calibrated on the machine at hand)


def holed_sphere(radius, n, seed):
    """n points on a sphere (Fibonacci lattice) but for 8 random caps of 30 degrees."""
    rng = random.Random(seed)
    holes = []
    for _ in range(8):
        z = rng.uniform(-0.8, 0.8)
        a = rng.uniform(0, 2 * math.pi)
        r = math.sqrt(1 - z * z)
        holes.append((r * math.cos(a), r * math.sin(a), z))
    golden = math.pi * (3.0 - math.sqrt(5.0))
    pts = []
    for i in range(n):
        z = 1.0 - 2.0 * (i + 0.5) / n
        r = math.sqrt(1.0 - z * z)
        d = (r * math.cos(golden * i), r * math.sin(golden * i), z)
        if any(d[0] * h[0] + d[1] * h[1] + d[2] * h[2] > math.cos(math.radians(15)) for h in holes):
            continue
        pts += [radius * c for c in d]
    return pts


def small_cloud(k):
    """A few hundred points on a 1 x 1 m patch 3 m away, a different direction each k."""
    a = 0.7 * k
    pts = []
    for i in range(20):
        for j in range(20):
            u, v = -0.5 + i / 20.0, -0.5 + j / 20.0
            pts += [3.0 * math.cos(a) - u * math.sin(a), 3.0 * math.sin(a) + u * math.cos(a), v]
    return pts


class SideBySide(unittest.TestCase):
    @classmethod
    def setUpClass(cls):
        rospy.init_node("map_server_side_by_side_test")
        for name in ("get_stats", "save_map", "get_frontiers"):
            rospy.wait_for_service(NS + name, timeout=120)
        cls.tmp = tempfile.mkdtemp(prefix="fragg_map_side_", dir="/tmp")
        cls.pub = rospy.Publisher(TOPIC, PointCloud2, queue_size=50)
        wait_for(lambda: cls.pub.get_num_connections() > 0, 60, "the node to subscribe")
        cls.stats = rospy.ServiceProxy(NS + "get_stats", GetStats)
        cls.sent = 0

    @classmethod
    def tearDownClass(cls):
        shutil.rmtree(cls.tmp, ignore_errors=True)

    def send(self, points):
        self.pub.publish(map_cloud(list(zip(points[0::3], points[1::3], points[2::3]))))
        type(self).sent += 1

    def frontiers(self, columns, rows):
        req = GetFrontiersRequest()
        req.k = 3
        req.sensor = "lidar"
        req.rays = [columns, rows]
        req.max_range = 12.0
        return rospy.ServiceProxy(NS + "get_frontiers", GetFrontiers)(req)

    def test_long_query_holds_nothing_back(self):
        self.send(holed_sphere(6.0, 60000, 1))
        wait_for(lambda: self.stats().stats.scans >= 1, 60, "the sphere inserted")
        # Calibration: rays scaled until one call takes LONG_S (the time grows with the rays).
        columns, rows = 90, 8
        for _ in range(8):
            t = time.monotonic()
            res = self.frontiers(columns, rows)
            took = time.monotonic() - t
            self.assertTrue(res.success, res.message)
            self.assertGreater(len(res.clusters), 0, res.message)
            if took >= LONG_S:
                break
            scale = min(16.0, max(1.5, 1.3 * LONG_S / max(took, 0.01)))
            columns = int(columns * math.sqrt(scale)) + 1
            rows = int(rows * math.sqrt(scale)) + 1
        self.assertGreaterEqual(took, LONG_S, "could not make get_frontiers long")
        scans_before = self.stats().stats.scans

        long_call = {}

        def run_long():
            long_call["start"] = time.monotonic()
            long_call["res"] = self.frontiers(columns, rows)
            long_call["end"] = time.monotonic()

        thread = threading.Thread(target=run_long, daemon=True)
        thread.start()
        time.sleep(0.5)  # the request is on its way
        stats_calls, save_calls = [], []
        save = rospy.ServiceProxy(NS + "save_map", SaveMap)
        k = 0
        while thread.is_alive() and k < 200:
            self.send(small_cloud(k))
            t = time.monotonic()
            s = self.stats()
            stats_calls.append((t, time.monotonic(), s.stats.scans))
            if k % 4 == 0:
                t = time.monotonic()
                r = save(os.path.join(self.tmp, "during_%d.fgm" % k))
                self.assertTrue(r.success, r.message)
                save_calls.append((t, time.monotonic()))
            k += 1
            time.sleep(0.2)
        thread.join(timeout=180)
        self.assertFalse(thread.is_alive(), "the long get_frontiers never answered")
        res = long_call["res"]
        self.assertTrue(res.success, res.message)
        end = long_call["end"]
        during = [c for c in stats_calls if c[1] < end]
        self.assertGreater(len(during), 0, "no get_stats answered while get_frontiers ran")
        self.assertGreater(len([c for c in save_calls if c[1] < end]), 0,
                           "no save_map answered while get_frontiers ran")
        self.assertGreater(max(c[2] for c in during), scans_before,
                           "no cloud was inserted while get_frontiers ran")
        # Every cloud inserted, none dropped; the counters sum to the clouds received.
        wait_for(lambda: self.stats().stats.scans >= self.sent, 60, "every cloud inserted")
        final = self.stats().stats
        self.assertEqual(final.scans, self.sent)
        self.assertEqual(final.dropped_clouds, 0)
        self.assertEqual(final.clouds_received, self.sent)
        self.assertEqual(final.clouds_received, final.clouds_inserted + final.dropped_clouds +
                         final.empty_clouds + final.clouds_in_flight)
        # The long answer is of the map before the clouds sent while it ran.
        self.assertLess(res.revision, self.frontiers(8, 4).revision)


if __name__ == "__main__":
    rostest.rosrun("fragg_map", "map_server_side_by_side", SideBySide)
