#!/usr/bin/python3
"""Writes a ROS bag of the real slambook2 RGB-D frames as an RGB-D driver publishes them.

  make_rgbd_bag.py OUT.bag RGBD_DIR

RGBD_DIR holds depth/N.pgm (640 x 480, 16-bit big-endian millimetres, 0 = no depth),
color/N.png (8-bit RGB) and pose.txt (line i: tx ty tz qx qy qz qw = T_world_camera of frame
i, camera optical frame). Intrinsics: the Kinect v1 of the frames (fx 518, fy 519, cx 325.5,
cy 253.5), as the dataset reader of `fragg_map build` assumes.

/camera/depth_registered/points (sensor_msgs/PointCloud2, frame camera_rgb_optical_frame),
frame i at t = i seconds: organised 640 x 480, the layout of depth_image_proc's point_cloud_xyzrgb
(float32 x y z at 0, 4, 8, rgb at 16, point_step 32), NaN where the depth is 0. The points are
computed exactly as fragg::depthToCloud does (double arithmetic, rounded to float32), so the bag
holds the same clouds as the folder.
/tf: map -> camera_link at each frame's stamp, so that map -> camera_rgb_optical_frame is the
     frame's pose; /tf_static: camera_link -> camera_rgb_optical_frame (REP 103: z forward,
     x right, y down in a body frame x forward, y left, z up).
"""
import argparse
import math
import os
import re
import struct
import zlib

import rosbag
import rospy
from geometry_msgs.msg import TransformStamped
from sensor_msgs.msg import PointCloud2, PointField
from tf2_msgs.msg import TFMessage

FX, FY, CX, CY, DEPTH_SCALE_M = 518.0, 519.0, 325.5, 253.5, 0.001
TOPIC = '/camera/depth_registered/points'
OPTICAL_FRAME = 'camera_rgb_optical_frame'
BODY_FRAME = 'camera_link'
# camera_link -> camera_rgb_optical_frame: the optical frame's axes in the body frame.
Q_BODY_OPTICAL = (-0.5, 0.5, -0.5, 0.5)


# ---- images --------------------------------------------------------------------------------

def read_pgm16(path):
    """Binary P5 PGM with 16-bit big-endian samples: (width, height, list of raw values)."""
    data = open(path, 'rb').read()
    match = re.match(rb'P5\s+(\d+)\s+(\d+)\s+(\d+)\s', data)
    assert match, path + ': not a binary PGM'
    width, height, maxval = (int(g) for g in match.groups())
    assert maxval > 255, path + ': expected 16-bit samples'
    values = struct.unpack_from('>%dH' % (width * height), data, match.end())
    return width, height, values


def paeth(a, b, c):
    p = a + b - c
    pa, pb, pc = abs(p - a), abs(p - b), abs(p - c)
    if pa <= pb and pa <= pc:
        return a
    return b if pb <= pc else c


def read_png_rgb8(path):
    """8-bit RGB, non-interlaced PNG (the colour frames): (width, height, bytes RGBRGB...)."""
    data = open(path, 'rb').read()
    assert data[:8] == b'\x89PNG\r\n\x1a\n', path + ': not a PNG'
    pos, idat, header = 8, [], None
    while pos < len(data):
        length, kind = struct.unpack_from('>I4s', data, pos)
        body = data[pos + 8:pos + 8 + length]
        if kind == b'IHDR':
            header = struct.unpack('>IIBBBBB', body)
        elif kind == b'IDAT':
            idat.append(body)
        pos += 12 + length
    width, height, depth, colour, _, _, interlace = header
    assert (depth, colour, interlace) == (8, 2, 0), path + ': expected 8-bit RGB, no interlace'
    raw = zlib.decompress(b''.join(idat))
    stride, bpp = 3 * width, 3
    out = bytearray(stride * height)
    prev = bytearray(stride)
    for y in range(height):
        kind = raw[y * (stride + 1)]
        line = bytearray(raw[y * (stride + 1) + 1:(y + 1) * (stride + 1)])
        if kind == 1:
            for i in range(bpp, stride):
                line[i] = (line[i] + line[i - bpp]) & 0xFF
        elif kind == 2:
            line = bytearray((a + b) & 0xFF for a, b in zip(line, prev))
        elif kind == 3:
            for i in range(stride):
                left = line[i - bpp] if i >= bpp else 0
                line[i] = (line[i] + ((left + prev[i]) >> 1)) & 0xFF
        elif kind == 4:
            for i in range(stride):
                left = line[i - bpp] if i >= bpp else 0
                up_left = prev[i - bpp] if i >= bpp else 0
                line[i] = (line[i] + paeth(left, prev[i], up_left)) & 0xFF
        else:
            assert kind == 0, '%s: unknown PNG filter %d' % (path, kind)
        out[y * stride:(y + 1) * stride] = line
        prev = line
    return width, height, bytes(out)


# ---- messages ------------------------------------------------------------------------------

def cloud_msg(stamp, depth, rgb):
    width, height, raw = depth
    assert (rgb[0], rgb[1]) == (width, height), 'colour and depth sizes differ'
    colours = rgb[2]
    msg = PointCloud2()
    msg.header.stamp = stamp
    msg.header.frame_id = OPTICAL_FRAME
    msg.height, msg.width = height, width
    msg.fields = [PointField('x', 0, PointField.FLOAT32, 1),
                  PointField('y', 4, PointField.FLOAT32, 1),
                  PointField('z', 8, PointField.FLOAT32, 1),
                  PointField('rgb', 16, PointField.FLOAT32, 1)]
    msg.is_bigendian = False
    msg.point_step = 32
    msg.row_step = 32 * width
    msg.is_dense = False
    row_format = '<' + '3f4xI12x' * width
    nan = float('nan')
    rows = []
    for v in range(height):
        values = []
        for u in range(width):
            i = v * width + u
            r, g, b = colours[3 * i:3 * i + 3]
            packed = (r << 16) | (g << 8) | b  # PCL's rgb: 0x00RRGGBB read as a float32
            d = raw[i]
            if d == 0:
                values += (nan, nan, nan, packed)
            else:
                z_m = d * DEPTH_SCALE_M  # the same double arithmetic as fragg::depthToCloud
                values += ((u - CX) * z_m / FX, (v - CY) * z_m / FY, z_m, packed)
        rows.append(struct.pack(row_format, *values))
    msg.data = b''.join(rows)
    return msg


def transform_msg(stamp, parent, child, t, q):
    msg = TransformStamped()
    msg.header.stamp = stamp
    msg.header.frame_id = parent
    msg.child_frame_id = child
    msg.transform.translation.x, msg.transform.translation.y, msg.transform.translation.z = t
    (msg.transform.rotation.x, msg.transform.rotation.y, msg.transform.rotation.z,
     msg.transform.rotation.w) = q
    return msg


def quat_mul(a, b):
    ax, ay, az, aw = a
    bx, by, bz, bw = b
    return (aw * bx + ax * bw + ay * bz - az * by,
            aw * by - ax * bz + ay * bw + az * bx,
            aw * bz + ax * by - ay * bx + az * bw,
            aw * bw - ax * bx - ay * by - az * bz)


def normalised(q):
    n = math.sqrt(sum(c * c for c in q))
    return tuple(c / n for c in q)


def main():
    parser = argparse.ArgumentParser(description=__doc__.split('\n')[0])
    parser.add_argument('out')
    parser.add_argument('rgbd_dir')
    args = parser.parse_args()

    poses = [[float(v) for v in line.split()]
             for line in open(os.path.join(args.rgbd_dir, 'pose.txt')) if line.strip()]
    q_optical_body = (-Q_BODY_OPTICAL[0], -Q_BODY_OPTICAL[1], -Q_BODY_OPTICAL[2],
                      Q_BODY_OPTICAL[3])
    with rosbag.Bag(args.out + '.tmp', 'w') as bag:
        t0 = rospy.Time.from_sec(0.5)
        bag.write('/tf_static', TFMessage([transform_msg(t0, BODY_FRAME, OPTICAL_FRAME,
                                                         (0.0, 0.0, 0.0), Q_BODY_OPTICAL)]), t0)
        for i, pose in enumerate(poses, start=1):
            stamp = rospy.Time.from_sec(float(i))
            # T_map_body = T_map_optical * T_optical_body; the mount has no translation.
            q_map_body = normalised(quat_mul(normalised(pose[3:7]), q_optical_body))
            bag.write('/tf', TFMessage([transform_msg(stamp, 'map', BODY_FRAME, pose[0:3],
                                                      q_map_body)]), stamp)
            depth = read_pgm16(os.path.join(args.rgbd_dir, 'depth', '%d.pgm' % i))
            rgb = read_png_rgb8(os.path.join(args.rgbd_dir, 'color', '%d.png' % i))
            bag.write(TOPIC, cloud_msg(stamp, depth, rgb), stamp)
    os.replace(args.out + '.tmp', args.out)  # no half-written bag on failure


if __name__ == '__main__':
    main()
