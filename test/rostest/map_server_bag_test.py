#!/usr/bin/python3
"""rostest of the map server on a recorded bag: the checks of map_server_checks.py, and, with
the private parameter `octomap_agreement` (a fraction), the map saved through ~save_map
against OctoMap's own map of the same bag (`fragg_map octomap-build`: liboctomap's
insertPointCloud, poses from the bag's tf, the node's resolution and max range): at least that
share of the cells either map knows must have the same state. States follow OctoMap's rule
(every observed cell known, occupied iff p >= 0.5, `compare --octomap-threshold`), as
octomap_server users see them: a .bt keeps only occupied or free per cell, not its
probability, so each map's unknown band cannot be applied to it."""
import json
import os
import subprocess

import rospy
import rostest

from map_server_checks import NS, MapServerBagChecks


class MapServerBagTest(MapServerBagChecks):
    def test_4_saved_map_agrees_with_octomap(self):
        least = rospy.get_param("~octomap_agreement", 0.0)
        if least <= 0.0:
            self.skipTest("no octomap_agreement asked for on this bag")
        bt = os.path.join(self.tmp, "octomap.bt")
        max_range = float(rospy.get_param(NS + "sensor_model/max_range", 100.0))  # the server's default
        subprocess.run([self.cli, "octomap-build", rospy.get_param("~bag"), "-o", bt,
                        "--topic", rospy.get_param("~topic"),
                        "--frame", rospy.get_param("~frame", "map"),
                        "--resolution", repr(float(rospy.get_param(NS + "resolution"))),
                        "--max-range", repr(max_range)],
                       check=True, stdout=subprocess.DEVNULL)
        out = subprocess.run([self.cli, "compare", bt, self.node_map(), "--json",
                              "--octomap-threshold"], check=True, stdout=subprocess.PIPE).stdout
        cmp = json.loads(out)
        differ = cmp["known_in_either"] - cmp["agreeing"]
        rospy.loginfo("node map vs OctoMap: %d of %d cells either knows differ (%.4f %% agree)",
                      differ, cmp["known_in_either"], 100.0 * cmp["agreement_in_either"])
        self.assertGreater(cmp["known_in_either"], 100000, cmp)
        self.assertGreaterEqual(cmp["agreement_in_either"], least,
                                "%d of %d cells differ: %s" %
                                (differ, cmp["known_in_either"], cmp["confusion"]))


if __name__ == "__main__":
    rostest.rosrun("fragg_map", "map_server_bag", MapServerBagTest)
