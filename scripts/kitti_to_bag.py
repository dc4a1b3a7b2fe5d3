#!/usr/bin/python3
"""Writes a ROS bag from a KITTI-style LiDAR folder (the simulator's W1, scripts/make_workloads.sh).

  kitti_to_bag.py KITTI_DIR OUT.bag [--scans N] [--start-s T]

KITTI_DIR: velodyne/NNNNNN.bin (float32 x y z intensity), poses.txt (3 x 4 row-major per scan,
the sensor's pose in the map frame, with calib.txt Tr = identity as the simulator writes it) and
times.txt (seconds). The bag: /points (sensor_msgs/PointCloud2, frame "lidar", x y z intensity
float32, point_step 16, the .bin bytes as they are) at start_s + time, and /tf map -> lidar at
the same stamps. Written to OUT.bag.tmp and renamed.
"""
import argparse
import math
import os

import rosbag
import rospy
from geometry_msgs.msg import TransformStamped
from sensor_msgs.msg import PointCloud2, PointField
from tf2_msgs.msg import TFMessage


def quat_from_rot(R):
    trace = R[0][0] + R[1][1] + R[2][2]
    if trace > 0:
        s = math.sqrt(trace + 1.0) * 2
        q = ((R[2][1] - R[1][2]) / s, (R[0][2] - R[2][0]) / s, (R[1][0] - R[0][1]) / s, s / 4)
    elif R[0][0] > R[1][1] and R[0][0] > R[2][2]:
        s = math.sqrt(1.0 + R[0][0] - R[1][1] - R[2][2]) * 2
        q = (s / 4, (R[0][1] + R[1][0]) / s, (R[0][2] + R[2][0]) / s, (R[2][1] - R[1][2]) / s)
    elif R[1][1] > R[2][2]:
        s = math.sqrt(1.0 + R[1][1] - R[0][0] - R[2][2]) * 2
        q = ((R[0][1] + R[1][0]) / s, s / 4, (R[1][2] + R[2][1]) / s, (R[0][2] - R[2][0]) / s)
    else:
        s = math.sqrt(1.0 + R[2][2] - R[0][0] - R[1][1]) * 2
        q = ((R[0][2] + R[2][0]) / s, (R[1][2] + R[2][1]) / s, s / 4, (R[1][0] - R[0][1]) / s)
    n = math.sqrt(sum(c * c for c in q))
    return tuple(c / n for c in q)


def check_identity_calib(folder):
    path = os.path.join(folder, 'calib.txt')
    if not os.path.exists(path):
        return
    for line in open(path):
        if line.startswith('Tr:'):
            values = [float(v) for v in line.split()[1:]]
            if values != [1, 0, 0, 0, 0, 1, 0, 0, 0, 0, 1, 0]:
                raise SystemExit('kitti_to_bag: ' + path + ': Tr is not the identity')


def cloud_msg(stamp, data):
    if len(data) % 16:
        raise SystemExit('kitti_to_bag: a .bin size is not a multiple of 16 bytes')
    msg = PointCloud2()
    msg.header.stamp = stamp
    msg.header.frame_id = 'lidar'
    msg.height, msg.width = 1, len(data) // 16
    msg.fields = [PointField(name, 4 * i, PointField.FLOAT32, 1)
                  for i, name in enumerate(('x', 'y', 'z', 'intensity'))]
    msg.is_bigendian = False
    msg.point_step, msg.row_step = 16, len(data)
    msg.is_dense = True
    msg.data = data
    return msg


def tf_msg(stamp, pose):
    R = [pose[0:3], pose[4:7], pose[8:11]]
    q = quat_from_rot(R)
    t = TransformStamped()
    t.header.stamp = stamp
    t.header.frame_id = 'map'
    t.child_frame_id = 'lidar'
    t.transform.translation.x, t.transform.translation.y, t.transform.translation.z = (
        pose[3], pose[7], pose[11])
    (t.transform.rotation.x, t.transform.rotation.y, t.transform.rotation.z,
     t.transform.rotation.w) = q
    return TFMessage([t])


def main():
    parser = argparse.ArgumentParser(description=__doc__.split('\n')[0])
    parser.add_argument('folder')
    parser.add_argument('out')
    parser.add_argument('--scans', type=int, default=0, help='first N scans (0: all)')
    parser.add_argument('--start-s', type=float, default=1.0, help='stamp of time 0 [s]')
    args = parser.parse_args()

    check_identity_calib(args.folder)
    scans_dir = os.path.join(args.folder, 'velodyne')
    files = sorted(f for f in os.listdir(scans_dir) if f.endswith('.bin'))
    poses = [[float(v) for v in l.split()] for l in open(os.path.join(args.folder, 'poses.txt'))
             if l.strip()]
    times = [float(l) for l in open(os.path.join(args.folder, 'times.txt')) if l.strip()]
    if not (len(files) == len(poses) == len(times)):
        raise SystemExit('kitti_to_bag: %d scans, %d poses, %d times' %
                         (len(files), len(poses), len(times)))
    count = len(files) if args.scans <= 0 else min(args.scans, len(files))
    with rosbag.Bag(args.out + '.tmp', 'w') as bag:
        for i in range(count):
            stamp = rospy.Time.from_sec(args.start_s + times[i])
            bag.write('/tf', tf_msg(stamp, poses[i]), stamp)
            with open(os.path.join(scans_dir, files[i]), 'rb') as f:
                bag.write('/points', cloud_msg(stamp, f.read()), stamp)
    os.replace(args.out + '.tmp', args.out)
    print('kitti_to_bag: %d scans -> %s' % (count, args.out))


if __name__ == '__main__':
    main()
