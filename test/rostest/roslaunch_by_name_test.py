#!/usr/bin/python3
"""roslaunch by package name: each launch file of fragg_map resolves to one file (a catkin
workspace inside the package, linked back to it, makes roslaunch find dozens of copies and
refuse), and `roslaunch fragg_map fragg_map.launch` starts a server that answers ~get_stats."""
import os
import signal
import subprocess
import time
import unittest

import roslib.packages
import rospkg
import rospy
import rostest

from fragg_map.srv import GetStats


class RoslaunchByNameTest(unittest.TestCase):
    def test_1_every_launch_file_resolves_once(self):
        launch_dir = os.path.join(rospkg.RosPack().get_path("fragg_map"), "launch")
        names = sorted(f for f in os.listdir(launch_dir) if f.endswith(".launch"))
        self.assertIn("fragg_map.launch", names)
        for name in names:
            found = roslib.packages.find_resource("fragg_map", name)
            self.assertEqual(len(found), 1, "%s found %d times: %s" % (name, len(found),
                                                                        found[:3]))
        out = subprocess.run(["roslaunch", "--files", "fragg_map", "fragg_map.launch"],
                             stdout=subprocess.PIPE, stderr=subprocess.STDOUT, text=True,
                             timeout=60)
        self.assertEqual(out.returncode, 0, out.stdout)
        self.assertIn(os.path.join(launch_dir, "fragg_map.launch"), out.stdout)

    def test_2_the_server_starts_through_it(self):
        rospy.init_node("roslaunch_by_name_test")
        env = dict(os.environ, ROSCONSOLE_STDOUT_LINE_BUFFERED="1")
        proc = subprocess.Popen(["roslaunch", "fragg_map", "fragg_map.launch", "backend:=cpu"],
                                stdout=subprocess.PIPE, stderr=subprocess.STDOUT, text=True,
                                env=env, start_new_session=True)
        try:
            rospy.wait_for_service("/fragg_map/get_stats", timeout=60)
            res = rospy.ServiceProxy("/fragg_map/get_stats", GetStats)()
            self.assertTrue(res.success, res.message)
            self.assertEqual(res.stats.backend, "cpu")
        finally:
            os.killpg(proc.pid, signal.SIGINT)
            try:
                out, _ = proc.communicate(timeout=30)
            except subprocess.TimeoutExpired:
                os.killpg(proc.pid, signal.SIGKILL)
                out, _ = proc.communicate()
        self.assertNotIn("multiple files named", out)


if __name__ == "__main__":
    rostest.rosrun("fragg_map", "roslaunch_by_name", RoslaunchByNameTest)
