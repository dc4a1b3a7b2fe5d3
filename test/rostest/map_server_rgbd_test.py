#!/usr/bin/python3
"""rostest of the map server on the RGB-D bag (make_rgbd_bag.py): the checks of
map_server_checks.py, and the bag's map against `fragg_map build` on the image folder the bag
was made from (private parameter `dataset`): the bag carries the same clouds and poses."""
import os

import rospy
import rostest

from map_server_checks import MapServerBagChecks


class MapServerRgbdTest(MapServerBagChecks):
    def test_3b_saved_map_equals_dataset_build(self):
        ref = os.path.join(self.tmp, "dataset.fgm")
        self.cli_build(rospy.get_param("~dataset"), ref)
        cmp = self.compare(ref, self.node_map())
        self.assertGreater(cmp["known_in_a"], 0)
        self.assertEqual(cmp["known_in_a"], cmp["known_in_b"], cmp)
        self.assertEqual(cmp["agreeing"], cmp["known_in_either"], cmp)


if __name__ == "__main__":
    rostest.rosrun("fragg_map", "map_server_rgbd", MapServerRgbdTest)
