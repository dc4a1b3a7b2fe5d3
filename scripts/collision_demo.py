#!/usr/bin/python3
"""Asks a running fragg_map server for a collision check that rviz can show (the picture in
docs/ros.md; scripts/render_rviz.sh --collision-demo runs it): a robot-sized box (0.6 x 0.4 x
0.3 m) at waypoints on a straight path from START towards the nearest occupied cell at the
start's height that has free space behind it, and 1.5 m beyond, checked pose by pose and as a
path. The `collisions` topic then shows the free poses green, the colliding ones red, the path
and its first colliding pose. Prints the answer.
Usage: collision_demo.py [--start X Y Z] [--waypoints N] [--timeout S]"""
import argparse
import math
import sys
import time

import rospy
from geometry_msgs.msg import PoseStamped
from sensor_msgs import point_cloud2
from sensor_msgs.msg import PointCloud2

from fragg_map.srv import CheckCollision, CheckCollisionRequest

ROBOT_M = [0.6, 0.4, 0.3]


def pose(p, yaw):
    ps = PoseStamped()
    ps.header.frame_id = "map"
    ps.pose.position.x, ps.pose.position.y, ps.pose.position.z = p
    ps.pose.orientation.z = math.sin(0.5 * yaw)
    ps.pose.orientation.w = math.cos(0.5 * yaw)
    return ps


def main():
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--start", type=float, nargs=3, default=[-10.0, 0.0, 1.42])
    ap.add_argument("--waypoints", type=int, default=12)
    ap.add_argument("--timeout", type=float, default=60.0)
    args = ap.parse_args(rospy.myargv()[1:])
    rospy.init_node("collision_demo", anonymous=True)
    rospy.wait_for_service("/fragg_map/check_collision", timeout=args.timeout)
    check = rospy.ServiceProxy("/fragg_map/check_collision", CheckCollision)
    cloud = rospy.wait_for_message("/occupied_cells", PointCloud2, timeout=args.timeout)
    start = tuple(args.start)
    cells = [tuple(p) for p in point_cloud2.read_points(cloud, ("x", "y", "z"))]
    # Obstacles at the start's height (not the ground), nearest first.
    walls = sorted((c for c in cells if abs(c[2] - start[2]) < 0.3 and
                    3.0 < math.dist(c, start) < 12.0), key=lambda c: math.dist(c, start))
    for wall in walls:
        d = [(w - s) / math.dist(wall, start) for w, s in zip(wall, start)]
        end = tuple(w + 1.5 * x for w, x in zip(wall, d))
        yaw = math.atan2(d[1], d[0])
        n = args.waypoints
        poses = [pose(tuple(s + (e - s) * i / (n - 1) for s, e in zip(start, end)), yaw)
                 for i in range(n)]
        ends = check(CheckCollisionRequest(poses=[poses[-1]], shape="box",
                                           dimensions=ROBOT_M))
        if not ends.success or ends.colliding:
            continue  # no free space behind this one
        res = check(CheckCollisionRequest(poses=poses, shape="box", dimensions=ROBOT_M,
                                          path_mode=True))
        print("wall cell %s; %s" % (tuple(round(v, 3) for v in wall), res.message))
        print("collides %s; path: segment %d, fraction %.3f, %d poses checked, %.2f ms" %
              (list(res.collides), res.path_first_segment, res.path_fraction,
               res.path_poses_checked, res.ms))
        return 0 if res.success else 1
    print("no obstacle with free space behind it near %s" % (start,), file=sys.stderr)
    return 1


if __name__ == "__main__":
    sys.exit(main())
