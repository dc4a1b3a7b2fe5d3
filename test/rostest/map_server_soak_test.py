#!/usr/bin/python3
"""The short soak in CI: scripts/soak.sh on the rostest's master (--use-master), the workspace
found from the fragg_map executable, output in a temporary folder; passes when the script's
checks pass (summary.json says which failed)."""
import json
import os
import shutil
import subprocess
import tempfile
import unittest

import rospkg
import rospy
import rostest
from catkin.find_in_workspaces import find_in_workspaces


# 75 s hold two or three cycles of a ~220 MiB map with transient copies of it on top: thirds
# of 20 s sample maps of whatever size the cycle had reached, so their medians moved 1.56-1.78 x
# without any leak (three clean-clone CI runs, docs/reliability.md). The short soak bounds the
# RSS just after each ~reset_map instead (soak.py's reset check, on by default: a node that
# keeps a map, a cloud or a copy per cycle fails it); the 30-minute run also checks the medians
# at 1.1 x. 0 here: the medians are reported, not checked.
RSS_RATIO = 0


class Soak(unittest.TestCase):
    def test_short_soak(self):
        rospy.init_node("map_server_soak_test")
        found = find_in_workspaces(["libexec"], project="fragg_map", path="fragg_map",
                                   first_match_only=True)
        self.assertTrue(found, "the fragg_map executable is not in the workspace")
        devel = found[0].split(os.sep + "lib" + os.sep + "fragg_map")[0]
        ws = os.path.dirname(devel)
        script = os.path.join(rospkg.RosPack().get_path("fragg_map"), "scripts", "soak.sh")
        out = tempfile.mkdtemp(prefix="fragg_map_soak_")
        try:
            seconds = rospy.get_param("~seconds")
            try:
                # The bound leaves room for the script's progress-bound waits (queue drain,
                # final phase) within the rostest's time-limit.
                run = subprocess.run(
                    ["bash", script, "--seconds", str(seconds), "--out", out,
                     "--bag", rospy.get_param("~bag"), "--rss-ratio", str(RSS_RATIO),
                     "--use-master", "--ws", ws, "--no-deps"],
                    stdout=subprocess.PIPE, stderr=subprocess.STDOUT, universal_newlines=True,
                    timeout=seconds + 330)
            except subprocess.TimeoutExpired as e:
                self.fail("soak.sh ran past %d s: %s" % (seconds + 330, (e.stdout or "")[-6000:]))
            summary = {}
            if os.path.exists(os.path.join(out, "summary.json")):
                with open(os.path.join(out, "summary.json")) as f:
                    summary = json.load(f)
            self.assertEqual(run.returncode, 0, run.stdout[-6000:])
            checks = summary.get("checks", {})
            self.assertTrue(checks and all(checks.values()), checks)
            # The mix plays the bag at 10 Hz for all but the final phase's 10 s: at least 70 %
            # of that must have been sent (the player shares the cores with the node).
            self.assertGreater(summary["clouds_sent"], int(0.7 * 10 * (seconds - 10)))
            self.assertIsInstance(summary["final_phase"]["compare"], dict, summary)
        finally:
            shutil.rmtree(out, ignore_errors=True)


if __name__ == "__main__":
    rostest.rosrun("fragg_map", "map_server_soak", Soak)
