#!/usr/bin/python3
"""rostest of the map server on a recorded bag: the checks of map_server_checks.py."""
import rostest

from map_server_checks import MapServerBagChecks


class MapServerBagTest(MapServerBagChecks):
    pass


if __name__ == "__main__":
    rostest.rosrun("fragg_map", "map_server_bag", MapServerBagTest)
