#!/usr/bin/python3
"""rostest of the map server on the smoke bag: incremental markers, the map saved through
~save_map against `fragg_map build` on the same bag, the services with good and bad
arguments, malformed clouds and a cloud whose transform never comes."""
import math
import os
import struct
import time

import rospy
import rostest
from geometry_msgs.msg import Point
from sensor_msgs.msg import PointCloud2, PointField
from visualization_msgs.msg import Marker

from fragg_map.srv import ClearBox, LoadMap, Reset
from map_server_checks import NS, MapServerBagChecks, wait_for


def xyz_fields(datatype=PointField.FLOAT32, size=4, names=("x", "y", "z")):
    return [PointField(name=n, offset=i * size, datatype=datatype, count=1)
            for i, n in enumerate(names)]


def cloud(fields, point_step, width, height, data, frame="lidar", row_step=None):
    msg = PointCloud2()
    msg.header.frame_id = frame
    msg.header.stamp = rospy.Time.now()
    msg.fields = fields
    msg.point_step = point_step
    msg.width = width
    msg.height = height
    msg.row_step = point_step * width if row_step is None else row_step
    msg.data = data
    msg.is_bigendian = False
    return msg


class MapServerSmokeTest(MapServerBagChecks):
    """The bag checks (tests 1-3), then malformed clouds, a cloud without tf and the services."""

    @classmethod
    def setUpClass(cls):
        super().setUpClass()
        for name in ("load_map", "reset_map", "clear_bbox"):
            rospy.wait_for_service(NS + name, timeout=60)
        cls.load = rospy.ServiceProxy(NS + "load_map", LoadMap)
        cls.reset = rospy.ServiceProxy(NS + "reset_map", Reset)
        cls.clear = rospy.ServiceProxy(NS + "clear_bbox", ClearBox)
        cls.pub = rospy.Publisher("/points", PointCloud2, queue_size=20)

    def test_4_malformed_clouds_are_rejected_map_intact(self):
        before = self.stats()
        good = struct.pack("<3f", 1.0, 2.0, 3.0) * 4
        nan = struct.pack("<3f", math.nan, math.nan, math.nan) * 4
        huge = struct.pack("<12f", 1e30, 0, 0, 0, 1e30, 0, 0, 0, -1e38, -1e38, 1e30, 0)
        bad = [
            cloud(xyz_fields(names=("x", "y")), 12, 4, 1, good),          # no z
            cloud(xyz_fields(), 8, 4, 1, good),                            # point_step too small
            cloud(xyz_fields(), 12, 4, 1, good[:40]),                      # data too short
            cloud(xyz_fields(PointField.INT16, 2), 6, 4, 1, b"\0" * 24),   # int16 fields
            cloud(xyz_fields(), 12, 1 << 20, 1 << 16, good),               # 2^36 points
            cloud(xyz_fields(), 12, 4, 1, good, row_step=40),              # row_step < a row
        ]
        no_point = [
            cloud(xyz_fields(), 12, 4, 1, nan),                            # all NaN
            cloud(xyz_fields(), 12, 4, 1, huge),                           # only 1e30 / -1e38
        ]
        # An empty cloud (drivers publish them) is neither malformed nor dropped: counted apart.
        empty = [cloud(xyz_fields(), 12, 0, 1, b""), cloud(xyz_fields(), 12, 5, 0, b"")]
        wait_for(lambda: self.pub.get_num_connections() > 0, 10, "the server to subscribe")
        for msg in empty + bad + no_point:
            self.pub.publish(msg)
            time.sleep(0.1)
        n = len(bad) + len(no_point)
        wait_for(lambda: self.stats().rejected_clouds >= before.rejected_clouds + n, 10,
                 "the malformed clouds to be rejected")
        after = self.stats()
        self.assertEqual(after.rejected_clouds, before.rejected_clouds + n)
        self.assertEqual(after.empty_clouds, before.empty_clouds + len(empty))
        self.assertEqual(after.dropped_clouds, before.dropped_clouds + n)
        self.assertEqual(after.rejected_malformed, before.rejected_malformed + len(bad))
        self.assertEqual(after.rejected_no_finite_point,
                         before.rejected_no_finite_point + len(no_point))
        self.assertEqual(after.points_invalid, before.points_invalid + 4)
        self.assertEqual(after.scans, before.scans)
        self.assertEqual(after.known_voxels, before.known_voxels)

    def test_5_cloud_without_tf_is_dropped_and_counted(self):
        before = self.stats()
        pts = struct.pack("<3f", 1.0, 0.0, 0.0) * 8
        self.pub.publish(cloud(xyz_fields(), 12, 8, 1, pts, frame="nowhere"))
        wait_for(lambda: self.stats().dropped_no_tf == before.dropped_no_tf + 1, 10,
                 "the cloud without tf to be dropped")
        # A cloud from the future (beyond any tf received): dropped after tf_tolerance.
        future = cloud(xyz_fields(), 12, 8, 1, pts)
        future.header.stamp = rospy.Time.now() + rospy.Duration(1000.0)
        self.pub.publish(future)
        wait_for(lambda: self.stats().dropped_no_tf == before.dropped_no_tf + 2, 10,
                 "the cloud from the future to be dropped")
        after = self.stats()
        self.assertEqual(after.scans, before.scans)
        self.assertEqual(after.known_voxels, before.known_voxels)

    def test_6_bad_service_arguments_leave_the_map_unchanged(self):
        before = self.stats().known_voxels
        p = Point
        for res in [
            self.save(os.path.join(self.tmp, "map.xyz")),
            self.save("/nonexistent-dir/map.fgm"),  # outside file_root (/tmp)
            self.save(os.path.join(self.tmp, "no-such-dir", "map.fgm")),
            self.save("../escape.fgm"),
            self.save(""),
            self.load("/etc/passwd.fgm"),
            self.load("../" + os.path.basename(self.tmp) + "/../../etc/x.fgm"),
            self.load(os.path.join(self.tmp, "missing.fgm")),
            self.load(os.path.join(self.tmp, "map.bt")),
            self.clear(p(1, 1, 1), p(0, 0, 0)),
            self.clear(p(math.nan, 0, 0), p(1, 1, 1)),
        ]:
            self.assertFalse(res.success)
            self.assertTrue(res.message)
        self.assertEqual(self.stats().known_voxels, before)
        self.assertFalse(os.path.exists("/escape.fgm"))

    def test_7_good_service_arguments(self):
        saved = os.path.join(self.tmp, "before_reset.fgm")
        self.assertTrue(self.save(saved).success)
        self.assertTrue(self.save(os.path.join(self.tmp, "map.bt")).success)
        self.assertGreater(os.path.getsize(os.path.join(self.tmp, "map.bt")), 0)
        known = self.stats().known_voxels
        res = self.clear(Point(-2, -2, -2), Point(2, 2, 2))
        self.assertTrue(res.success, res.message)
        cleared = self.stats().known_voxels
        self.assertLess(cleared, known)
        n = len(self.arrays)
        res = self.reset()
        self.assertTrue(res.success, res.message)
        self.assertEqual(self.stats().known_voxels, 0)
        self.assertEqual(self.stats().scans, 0)
        wait_for(lambda: any(m.action == Marker.DELETEALL
                             for a in self.arrays[n:] for m in a.markers), 10,
                 "a full marker republish after reset")
        # A path relative to file_root (/tmp here) names the same file.
        res = self.load(os.path.relpath(saved, rospy.get_param(NS + "file_root")))
        self.assertTrue(res.success, res.message)
        self.assertEqual(self.stats().known_voxels, known)


if __name__ == "__main__":
    rostest.rosrun("fragg_map", "map_server_smoke", MapServerSmokeTest)
