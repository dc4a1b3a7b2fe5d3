#!/usr/bin/python3
"""Writes a small ROS bag from the real small_gicp Velodyne scans, for the bag reader's test.

  make_test_bag.py OUT.bag PLY_DIR [--variant normal|two-topics|no-tf]

/velodyne_points (sensor_msgs/PointCloud2, frame "velodyne"):
  t=1.0  target.ply: float32 x y z intensity, unorganised, no-return (0,0,0) points dropped
  t=2.0  source.ply: float64 x y z + float32 intensity, organised 32 rows, no-return = NaN,
         frame_id "/velodyne" (leading slash, as old drivers wrote it)
  t=3.0  target.ply again, after the last /tf message: cannot be placed (extrapolation)
/tf: map -> odom (constant), odom -> base_link at 10 Hz over 0.5..2.5 s, chosen so that
     T_map_velodyne(2.0) = T_map_velodyne(1.0) * T_target_source (the scans align);
/tf_static: base_link -> velodyne (the sensor mount).
Variant two-topics adds /camera/points; variant no-tf writes only /tf_static.

Next to OUT.bag it writes OUT.bag.poses: per placeable cloud "stamp_ns" and the expected
T_map_velodyne (16 numbers, row-major), computed here from the published transforms.
"""
import argparse
import math
import struct

import rosbag
import rospy
from geometry_msgs.msg import TransformStamped
from sensor_msgs.msg import PointCloud2, PointField
from tf2_msgs.msg import TFMessage


# ---- rigid transforms as (R 3x3 list, t list) ---------------------------------------------

def quat_from_rpy(roll, pitch, yaw):
    cr, sr = math.cos(roll / 2), math.sin(roll / 2)
    cp, sp = math.cos(pitch / 2), math.sin(pitch / 2)
    cy, sy = math.cos(yaw / 2), math.sin(yaw / 2)
    return (sr * cp * cy - cr * sp * sy,  # x
            cr * sp * cy + sr * cp * sy,  # y
            cr * cp * sy - sr * sp * cy,  # z
            cr * cp * cy + sr * sp * sy)  # w


def rot_from_quat(q):
    x, y, z, w = q
    n = math.sqrt(x * x + y * y + z * z + w * w)
    x, y, z, w = x / n, y / n, z / n, w / n
    return [[1 - 2 * (y * y + z * z), 2 * (x * y - z * w), 2 * (x * z + y * w)],
            [2 * (x * y + z * w), 1 - 2 * (x * x + z * z), 2 * (y * z - x * w)],
            [2 * (x * z - y * w), 2 * (y * z + x * w), 1 - 2 * (x * x + y * y)]]


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


def compose(a, b):
    Ra, ta = a
    Rb, tb = b
    R = [[sum(Ra[i][k] * Rb[k][j] for k in range(3)) for j in range(3)] for i in range(3)]
    t = [sum(Ra[i][k] * tb[k] for k in range(3)) + ta[i] for i in range(3)]
    return R, t


def inverse(a):
    R, t = a
    Rt = [[R[j][i] for j in range(3)] for i in range(3)]
    return Rt, [-sum(Rt[i][k] * t[k] for k in range(3)) for i in range(3)]


def make(t, q):
    return rot_from_quat(q), list(t)


def published(a):
    """The transform as it goes into the bag (quaternion) and as tf2 will see it."""
    q = quat_from_rot(a[0])
    return make(a[1], q), q


def transform_msg(stamp, parent, child, a):
    (_, t), q = published(a)
    msg = TransformStamped()
    msg.header.stamp = stamp
    msg.header.frame_id = parent
    msg.child_frame_id = child
    msg.transform.translation.x, msg.transform.translation.y, msg.transform.translation.z = t
    (msg.transform.rotation.x, msg.transform.rotation.y, msg.transform.rotation.z,
     msg.transform.rotation.w) = q
    return msg


# ---- clouds --------------------------------------------------------------------------------

def read_ply(path):
    """Binary little-endian PLY with float x y z intensity (the small_gicp files)."""
    data = open(path, 'rb').read()
    end = data.index(b'end_header\n') + len(b'end_header\n')
    header = data[:end].decode('ascii').split('\n')
    count = int([l for l in header if l.startswith('element vertex')][0].split()[2])
    props = [l.split()[2] for l in header if l.startswith('property')]
    assert props == ['float', 'float', 'float', 'float'] or len(props) == 4, props
    return [struct.unpack_from('<4f', data, end + 16 * i) for i in range(count)]


def cloud_msg(stamp, frame, points, organised_rows=0, use_double=False):
    msg = PointCloud2()
    msg.header.stamp = stamp
    msg.header.frame_id = frame
    if use_double:
        msg.fields = [PointField('x', 0, PointField.FLOAT64, 1),
                      PointField('y', 8, PointField.FLOAT64, 1),
                      PointField('z', 16, PointField.FLOAT64, 1),
                      PointField('intensity', 24, PointField.FLOAT32, 1)]
        msg.point_step = 32  # 4 bytes of padding at the end
        fmt = '<3df4x'
    else:
        msg.fields = [PointField('x', 0, PointField.FLOAT32, 1),
                      PointField('y', 4, PointField.FLOAT32, 1),
                      PointField('z', 8, PointField.FLOAT32, 1),
                      PointField('intensity', 12, PointField.FLOAT32, 1)]
        msg.point_step = 16
        fmt = '<4f'
    if organised_rows:
        assert len(points) % organised_rows == 0
        msg.height = organised_rows
        msg.width = len(points) // organised_rows
    else:
        msg.height = 1
        msg.width = len(points)
    msg.row_step = msg.point_step * msg.width
    msg.is_bigendian = False
    msg.is_dense = not any(math.isnan(p[0]) for p in points)
    msg.data = b''.join(struct.pack(fmt, *p) for p in points)
    return msg


def main():
    parser = argparse.ArgumentParser(description=__doc__.split('\n')[0])
    parser.add_argument('out')
    parser.add_argument('ply_dir')
    parser.add_argument('--variant', choices=['normal', 'two-topics', 'no-tf'], default='normal')
    args = parser.parse_args()

    target = read_ply(args.ply_dir + '/target.ply')
    source = read_ply(args.ply_dir + '/source.ply')
    with open(args.ply_dir + '/T_target_source.txt') as f:
        m = [float(v) for v in f.read().split()]
    T_target_source = ([m[0:3], m[4:7], m[8:11]], [m[3], m[7], m[11]])

    T_map_odom, _ = published(make((1.0, -2.0, 0.0), quat_from_rpy(0.0, 0.0, 0.3)))
    T_base_velo, _ = published(make((0.2, 0.0, 1.5), quat_from_rpy(0.0, 0.02, 0.1)))
    T_odom_base1, _ = published(make((3.0, 4.0, 0.1), quat_from_rpy(0.01, -0.01, 0.5)))
    T_map_velo1 = compose(compose(T_map_odom, T_odom_base1), T_base_velo)
    T_odom_base2, _ = published(compose(compose(inverse(T_map_odom), compose(T_map_velo1, T_target_source)),
                                        inverse(T_base_velo)))
    T_map_velo2 = compose(compose(T_map_odom, T_odom_base2), T_base_velo)

    def odom_base(step):
        """odom -> base_link at 0.5 + 0.1 * step seconds; exact at 1.0 s and 2.0 s."""
        t = 0.5 + 0.1 * step
        if abs(t - 1.0) < 1e-9:
            return T_odom_base1
        if abs(t - 2.0) < 1e-9:
            return T_odom_base2
        # Elsewhere: a different pose, so a lookup at the wrong time gives a wrong answer.
        return published(make((3.0 + t, 4.0 - t, 0.1), quat_from_rpy(0.0, 0.0, 0.5 + t)))[0]

    with rosbag.Bag(args.out, 'w') as bag:
        t0 = rospy.Time.from_sec(0.1)
        bag.write('/tf_static', TFMessage([transform_msg(t0, 'base_link', 'velodyne', T_base_velo)]), t0)
        if args.variant != 'no-tf':
            for step in range(21):
                stamp = rospy.Time.from_sec(0.5 + 0.1 * step)
                bag.write('/tf', TFMessage([transform_msg(stamp, 'map', 'odom', T_map_odom),
                                            transform_msg(stamp, 'odom', 'base_link', odom_base(step))]),
                          stamp)
        nan = float('nan')
        t1, t2, t3 = rospy.Time.from_sec(1.0), rospy.Time.from_sec(2.0), rospy.Time.from_sec(3.0)
        valid_target = [p for p in target if (p[0], p[1], p[2]) != (0.0, 0.0, 0.0)]
        bag.write('/velodyne_points', cloud_msg(t1, 'velodyne', valid_target), t1)
        organised_source = [(nan, nan, nan, p[3]) if (p[0], p[1], p[2]) == (0.0, 0.0, 0.0) else p
                            for p in source]
        bag.write('/velodyne_points',
                  cloud_msg(t2, '/velodyne', organised_source, organised_rows=32, use_double=True), t2)
        bag.write('/velodyne_points', cloud_msg(t3, 'velodyne', valid_target[:1000]), t3)
        if args.variant == 'two-topics':
            bag.write('/camera/points', cloud_msg(t1, 'camera', valid_target[:100]), t1)

    with open(args.out + '.poses', 'w') as f:
        for stamp, T in ((t1, T_map_velo1), (t2, T_map_velo2)):
            R, t = T
            rows = [R[0] + [t[0]], R[1] + [t[1]], R[2] + [t[2]], [0.0, 0.0, 0.0, 1.0]]
            f.write('%d %s\n' % (stamp.to_nsec(), ' '.join(repr(v) for row in rows for v in row)))


if __name__ == '__main__':
    main()
