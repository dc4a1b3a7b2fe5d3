#!/usr/bin/python3
"""Autosave and recovery of the map server (issue 18): the node, started by this test with
autosave/period_s 1, is fed the bag's clouds (looped, fresh stamps) and SIGKILLed; restarted,
it must hold every cloud inserted up to one period (+ the time of a save) before the kill, its
map must equal `fragg_map build` on exactly the clouds it says it holds, it must continue that
map (more clouds: its scan count goes on), and a SIGINT must save the last state (a third start
sees it). The node's stderr/stdout go to the test's temporary folder."""
import os
import shutil
import signal
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
from sensor_msgs.msg import PointCloud2
from tf2_msgs.msg import TFMessage

import fgm_cells
from fragg_map.srv import GetStats, SaveMap

NODE = "fragg_map_autosave"
NS = "/" + NODE + "/"
PERIOD_S = 1.0


def wait_for(predicate, timeout_s, what):
    deadline = time.monotonic() + timeout_s
    while time.monotonic() < deadline:
        if predicate():
            return
        time.sleep(0.1)
    raise AssertionError("timed out waiting for " + what)


def scans_in(path):
    with open(path, "rb") as f:
        head = f.read(88)
    return struct.unpack_from("<Q", head, 80)[0]


class AutosaveRecovery(unittest.TestCase):
    @classmethod
    def setUpClass(cls):
        rospy.init_node("map_server_autosave_test")
        cls.tmp = tempfile.mkdtemp(prefix="fragg_map_autosave_")
        found = find_in_workspaces(["libexec"], project="fragg_map", path="fragg_map",
                                   first_match_only=True)
        assert found, "the fragg_map executable is not in the workspace"
        cls.cli = found[0]
        cls.bag = rospy.get_param("~bag")
        cls.clouds, cls.tf, cls.static = [], [], []
        with rosbag.Bag(cls.bag) as bag:
            for topic, msg, _ in bag.read_messages(topics=["/points", "/tf", "/tf_static"]):
                if topic == "/points":
                    cls.clouds.append(msg)
                elif topic == "/tf":
                    cls.tf.extend(msg.transforms)
                else:
                    cls.static.extend(msg.transforms)
        cls.placing = [[t for t in cls.tf if t.header.stamp == c.header.stamp]
                       for c in cls.clouds]
        cls.pub = rospy.Publisher("/autosave_points", PointCloud2, queue_size=50)
        cls.tf_pub = rospy.Publisher("/tf", TFMessage, queue_size=50)
        cls.static_pub = rospy.Publisher("/tf_static", TFMessage, queue_size=1, latch=True)
        cls.static_pub.publish(TFMessage(transforms=cls.static))
        for name, value in (("backend", "cpu"), ("frame_id", "map"), ("queue_size", 50),
                            ("file_root", cls.tmp), ("autosave/path", "robot/auto.fgm"),
                            ("autosave/period_s", PERIOD_S)):
            rospy.set_param(NS + name, value)
        cls.autosave = os.path.join(cls.tmp, "robot", "auto.fgm")
        cls.node = None
        cls.starts = 0

    @classmethod
    def tearDownClass(cls):
        if cls.node and cls.node.poll() is None:
            cls.node.kill()
            cls.node.wait()
        shutil.rmtree(cls.tmp, ignore_errors=True)

    @classmethod
    def start_node(cls):
        cls.starts += 1
        log = open(os.path.join(cls.tmp, "node%d.log" % cls.starts), "w")
        cls.node = subprocess.Popen(
            ["/usr/lib/nodelet/nodelet", "standalone", "fragg_map/MapServerNodelet",
             "__name:=" + NODE, "cloud_in:=/autosave_points"], stdout=log,
            stderr=subprocess.STDOUT)
        rospy.wait_for_service(NS + "get_stats", timeout=60)
        cls.get_stats = rospy.ServiceProxy(NS + "get_stats", GetStats, persistent=False)
        # The old node's service may still be registered: wait for the new one to answer.
        wait_for(lambda: cls.stats_or_none() is not None, 30, "the node's get_stats")

    @classmethod
    def stats_or_none(cls):
        try:
            res = cls.get_stats()
            return res.stats if res.success else None
        except (rospy.ServiceException, rospy.ROSException):
            return None

    @classmethod
    def log_of(cls, start):
        with open(os.path.join(cls.tmp, "node%d.log" % start)) as f:
            return f.read()

    def publish(self, i):
        now = rospy.Time.now()
        transforms = self.placing[i % len(self.clouds)]
        for t in transforms:
            t.header.stamp = now
        self.tf_pub.publish(TFMessage(transforms=transforms))
        cloud = self.clouds[i % len(self.clouds)]
        cloud.header.stamp = now
        time.sleep(0.005)
        self.pub.publish(cloud)

    def prefix_bag(self, n, path):
        """The first n clouds of the looped sequence as a bag (stamps 0.1 s apart)."""
        t0 = rospy.Time(1700000000)
        with rosbag.Bag(path, "w") as bag:
            bag.write("/tf_static", TFMessage(transforms=self.static), t0)
            for i in range(n):
                stamp = t0 + rospy.Duration(0.1 * (i + 1))
                transforms = self.placing[i % len(self.clouds)]
                for t in transforms:
                    t.header.stamp = stamp
                bag.write("/tf", TFMessage(transforms=transforms), stamp)
                cloud = self.clouds[i % len(self.clouds)]
                cloud.header.stamp = stamp
                bag.write("/points", cloud, stamp)

    def test_kill_restart_continue(self):
        self.start_node()
        self.assertIn("start map: empty (no autosave at", self.log_of(1))
        # Clouds at 5 Hz while get_stats is polled; SIGKILL after >= 4 autosave periods.
        history = []  # (monotonic time, scans, dropped)
        sent = [0]
        stop = threading.Event()

        def feed():
            while not stop.is_set():
                self.publish(sent[0])
                sent[0] += 1
                time.sleep(0.2)

        feeder = threading.Thread(target=feed, daemon=True)
        feeder.start()
        t_start = time.monotonic()
        while time.monotonic() - t_start < 5.5:
            s = self.stats_or_none()
            if s is not None:
                history.append((time.monotonic(), s.scans, s.dropped_clouds))
            time.sleep(0.05)
        self.node.send_signal(signal.SIGKILL)
        t_kill = time.monotonic()
        self.node.wait()
        stop.set()
        feeder.join()
        self.assertEqual(self.node.returncode, -signal.SIGKILL)
        self.assertTrue(history)
        self.assertEqual(history[-1][2], 0, "clouds were dropped before the kill")
        at_kill = history[-1][1]
        self.assertGreater(at_kill, 10)
        # Everything inserted one period (+ 1 s for the save itself) before the kill is kept.
        must_hold = max([s for t, s, _ in history if t <= t_kill - PERIOD_S - 1.0] + [0])
        self.assertGreater(must_hold, 0)
        self.assertTrue(os.path.exists(self.autosave))
        on_disk = scans_in(self.autosave)

        self.start_node()
        restarted = self.stats_or_none()
        self.assertGreaterEqual(restarted.scans, must_hold)
        self.assertLessEqual(restarted.scans, at_kill)
        self.assertEqual(restarted.scans, on_disk)
        self.assertIn("start map: autosave " + self.autosave + " (%d scans" % on_disk,
                      self.log_of(2))
        n = restarted.scans
        # The reloaded map is the map of exactly those n clouds.
        save = rospy.ServiceProxy(NS + "save_map", SaveMap)
        saved = os.path.join(self.tmp, "restarted.fgm")
        self.assertTrue(save(saved).success)
        prefix = os.path.join(self.tmp, "prefix.bag")
        self.prefix_bag(n, prefix)
        built = os.path.join(self.tmp, "built.fgm")
        subprocess.run([self.cli, "build", prefix, "-o", built, "--topic", "/points", "--frame",
                        "map"], check=True, stdout=subprocess.DEVNULL)
        mine, theirs = fgm_cells.read_blocks(saved), fgm_cells.read_blocks(built)
        self.assertTrue(mine[0])
        self.assertEqual(mine, theirs, "the recovered map differs from `fragg_map build` of "
                         "its %d clouds" % n)

        # The map continues: three more clouds, then SIGINT saves the last state.
        for i in range(3):
            self.publish(n + i)
            time.sleep(0.3)
        wait_for(lambda: (self.stats_or_none() or restarted).scans == n + 3, 30,
                 "three more scans")
        self.node.send_signal(signal.SIGINT)
        self.node.wait(timeout=60)
        self.assertEqual(scans_in(self.autosave), n + 3)
        self.assertIn("saved the map on shutdown", self.log_of(2))
        self.start_node()
        self.assertEqual(self.stats_or_none().scans, n + 3)
        for start in range(1, self.starts + 1):
            self.assertNotIn("[ERROR]", self.log_of(start))


if __name__ == "__main__":
    rostest.rosrun("fragg_map", "map_server_autosave", AutosaveRecovery)
