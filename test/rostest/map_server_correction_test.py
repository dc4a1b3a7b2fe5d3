#!/usr/bin/python3
"""rostest of loop-closure correction in the map server on the smoke bag: after the bag
checks (tests 1-3), ~correct_poses refuses bad arguments with the map unchanged, corrects
scans named by stamp (an unknown stamp is reported back, the rest corrected) with the changed
blocks' markers republished, and corrected_path (base_link poses; the node turns them into
sensor poses through tf base_link -> lidar) corrects the scans that moved: first to the ground
truth, then back to the odometry poses, after which the saved map agrees with the map saved
before any correction."""
import math
import os
import time

import rosbag
import rospy
import rostest
from geometry_msgs.msg import Pose, PoseStamped
from nav_msgs.msg import Path
from visualization_msgs.msg import Marker

from fragg_map.srv import CorrectPoses
from map_server_checks import NS, MapServerBagChecks, wait_for

AGREEMENT = 0.995  # issue 6: known cells in the same state after correcting back


# Rigid transforms as (t, q): t = (x, y, z), q = (x, y, z, w).
def q_mul(a, b):
    ax, ay, az, aw = a
    bx, by, bz, bw = b
    return (aw * bx + ax * bw + ay * bz - az * by,
            aw * by - ax * bz + ay * bw + az * bx,
            aw * bz + ax * by - ay * bx + az * bw,
            aw * bw - ax * bx - ay * by - az * bz)


def rotate(q, v):
    x, y, z, _ = q_mul(q_mul(q, (v[0], v[1], v[2], 0.0)), (-q[0], -q[1], -q[2], q[3]))
    return (x, y, z)


def compose(a, b):
    ta, qa = a
    tb, qb = b
    r = rotate(qa, tb)
    return ((ta[0] + r[0], ta[1] + r[1], ta[2] + r[2]), q_mul(qa, qb))


def from_msg(t, q):
    return ((t.x, t.y, t.z), (q.x, q.y, q.z, q.w))


def to_pose(T):
    p = Pose()
    p.position.x, p.position.y, p.position.z = T[0]
    p.orientation.x, p.orientation.y, p.orientation.z, p.orientation.w = T[1]
    return p


def moved_beyond(a, b, min_translation_m, min_rotation_rad):
    """The node's rule (pose_correction.h): origins farther apart than min_translation_m, or
    a relative rotation of more than min_rotation_rad."""
    d = math.sqrt(sum((x - y) ** 2 for x, y in zip(a[0], b[0])))
    qa, qb = a[1], b[1]
    dot = abs(sum(x * y for x, y in zip(qa, qb)))
    angle = 2.0 * math.acos(min(1.0, dot))
    return d > min_translation_m or angle > min_rotation_rad


def shifted(T, dx, dy):
    return ((T[0][0] + dx, T[0][1] + dy, T[0][2]), T[1])


def read_bag(path, topic):
    """Cloud stamps, odometry base poses (map -> odom -> base_link from /tf) at those stamps,
    T_base_lidar (/tf_static) and the ground-truth path."""
    stamps, T_odom_base, T_map_odom = [], {}, {}
    T_base_lidar, truth = None, None
    with rosbag.Bag(path) as bag:
        for name, msg, _ in bag.read_messages(topics=[topic, "/tf", "/tf_static",
                                                      "/ground_truth/path"]):
            if name == topic:
                stamps.append(msg.header.stamp)
            elif name == "/ground_truth/path":
                truth = msg
            else:
                for tf in msg.transforms:
                    T = from_msg(tf.transform.translation, tf.transform.rotation)
                    key = tf.header.stamp.to_nsec()
                    if tf.child_frame_id == "lidar":
                        T_base_lidar = T
                    elif tf.child_frame_id == "base_link":
                        T_odom_base[key] = T
                    elif tf.child_frame_id == "odom":
                        T_map_odom[key] = T
    base = [compose(T_map_odom[s.to_nsec()], T_odom_base[s.to_nsec()]) for s in stamps]
    return stamps, base, T_base_lidar, truth


class MapServerCorrectionTest(MapServerBagChecks):
    @classmethod
    def setUpClass(cls):
        super().setUpClass()
        rospy.wait_for_service(NS + "correct_poses", timeout=60)
        cls.correct = rospy.ServiceProxy(NS + "correct_poses", CorrectPoses)
        cls.path_pub = rospy.Publisher("/corrected_path", Path, queue_size=2)
        cls.stamps, cls.base, cls.T_base_lidar, cls.truth = read_bag(
            rospy.get_param("~bag"), rospy.get_param("~topic"))
        cls.sensor = [compose(T, cls.T_base_lidar) for T in cls.base]

    def saved(self, name):
        path = os.path.join(self.tmp, name)
        res = self.save(path)
        self.assertTrue(res.success, res.message)
        return path

    def assert_same_map(self, path):
        cmp = self.compare(self.node_map(), path)  # node.fgm: saved once after the bag
        self.assertEqual(cmp["agreeing"], cmp["known_in_either"], cmp)

    def test_4_bad_correct_poses_arguments_leave_the_map_unchanged(self):
        self.assertEqual(len(self.stamps), self.scans)
        self.node_map()
        before = self.stats()
        self.assertEqual(before.scans_kept, self.scans)
        good = to_pose(self.sensor[0])
        nan = to_pose(self.sensor[0])
        nan.orientation.w = math.nan
        long_q = to_pose(self.sensor[0])
        long_q.orientation.x, long_q.orientation.y = 0.0, 0.0
        long_q.orientation.z, long_q.orientation.w = 0.0, 2.0
        s0, s1 = self.stamps[0], self.stamps[1]
        for stamps, poses, why in [
            ([s0, s1], [good], "arrays of different lengths"),
            ([], [], "nothing to correct"),
            ([s0, s1], [good, nan], "a NaN quaternion"),
            ([s0], [long_q], "a quaternion of norm 2"),
            ([s0, s0], [good, good], "one scan named twice"),
        ]:
            res = self.correct(stamps, poses)
            self.assertFalse(res.success, why)
            self.assertTrue(res.message, why)
            self.assertEqual(res.corrected, 0, why)
        after = self.stats()
        self.assertEqual(after.known_voxels, before.known_voxels)
        self.assertEqual(after.corrections, before.corrections)
        self.assertEqual(after.corrected_scans, before.corrected_scans)
        self.assert_same_map(self.saved("after_bad.fgm"))

    def test_5_correct_poses_moves_scans_reports_unknown_stamps(self):
        before = self.stats()
        picked = [3, 4, 5]
        unknown = rospy.Time(self.stamps[-1].to_sec() + 5.0)
        stamps = [self.stamps[i] for i in picked] + [unknown]
        moved = [to_pose(shifted(self.sensor[i], 0.0, 0.4)) for i in picked] + [
            to_pose(self.sensor[0])]
        n = len(self.arrays)
        res = self.correct(stamps, moved)
        self.assertTrue(res.success, res.message)
        self.assertEqual(res.corrected, len(picked))
        self.assertEqual(list(res.unknown_stamps), [unknown])
        self.assertGreater(res.ms, 0.0)
        rospy.loginfo("~correct_poses: %d scans in %.1f ms (insertion mean %.1f ms)",
                      res.corrected, res.ms, self.stats().insertion_ms_mean)
        after = self.stats()
        self.assertEqual(after.corrections, before.corrections + 1)
        self.assertEqual(after.corrected_scans, before.corrected_scans + len(picked))
        self.assertEqual(after.scans_kept, self.scans)
        self.assertNotEqual(after.known_voxels, before.known_voxels)
        # The changed blocks' markers go out incrementally (no full republish).
        wait_for(lambda: any(a.markers for a in self.arrays[n:]), 10,
                 "markers after the correction")
        update = [a for a in self.arrays[n:] if a.markers]
        self.assertFalse(any(m.action == Marker.DELETEALL for a in update for m in a.markers))
        # Back to the poses of the bag: the map agrees with the map before.
        res = self.correct([self.stamps[i] for i in picked],
                           [to_pose(self.sensor[i]) for i in picked])
        self.assertTrue(res.success, res.message)
        self.assertEqual(res.corrected, len(picked))
        self.assertEqual(len(res.unknown_stamps), 0)
        cmp = self.compare(self.node_map(), self.saved("service_back.fgm"))
        self.assertGreaterEqual(cmp["agreement_in_either"], AGREEMENT, cmp)
        rospy.loginfo("~correct_poses: agreement after moving back %.5f",
                      cmp["agreement_in_either"])

    def publish_path(self, poses, stamps):
        path = Path()
        path.header.frame_id = "map"
        path.header.stamp = stamps[-1]
        for T, stamp in zip(poses, stamps):
            p = PoseStamped()
            p.header.frame_id = "map"
            p.header.stamp = stamp
            p.pose = to_pose(T)
            path.poses.append(p)
        wait_for(lambda: self.path_pub.get_num_connections() > 0, 10,
                 "the server to subscribe corrected_path")
        self.path_pub.publish(path)

    def test_6_corrected_path_corrects_and_back(self):
        self.assertIsNotNone(self.truth, "the bag has no /ground_truth/path")
        truth = [from_msg(p.pose.position, p.pose.orientation) for p in self.truth.poses]
        truth_stamps = [p.header.stamp for p in self.truth.poses]
        self.assertEqual(truth_stamps, self.stamps)
        # The scans whose sensor pose the ground truth moves beyond the thresholds.
        min_t = rospy.get_param(NS + "correction/min_translation")
        min_r = rospy.get_param(NS + "correction/min_rotation")
        truth_sensor = [compose(T, self.T_base_lidar) for T in truth]
        expected = sum(moved_beyond(a, b, min_t, min_r)
                       for a, b in zip(self.sensor, truth_sensor))
        self.assertGreater(expected, 0, "the odometry does not drift beyond the thresholds")
        self.assertLess(expected, self.scans, "every scan moves: the thresholds go untested")
        before = self.stats()
        self.publish_path(truth, truth_stamps)
        wait_for(lambda: self.stats().corrections == before.corrections + 1, 20,
                 "a correction from corrected_path")
        corrected = self.stats()
        self.assertEqual(corrected.corrected_scans - before.corrected_scans, expected)
        self.assertNotEqual(corrected.known_voxels, before.known_voxels)
        rospy.loginfo("corrected_path: %d of %d scans moved in %.1f ms (insertion mean %.1f ms)",
                      expected, self.scans, corrected.correction_ms_last,
                      corrected.insertion_ms_mean)
        # The same path again moves nothing: every pose is now within the thresholds.
        self.publish_path(truth, truth_stamps)
        time.sleep(2.0)
        self.assertEqual(self.stats().corrections, corrected.corrections)
        # Back to the odometry poses: the same scans move back.
        self.publish_path(self.base, self.stamps)
        wait_for(lambda: self.stats().corrections == before.corrections + 2, 20,
                 "the correction back")
        after = self.stats()
        self.assertEqual(after.corrected_scans - before.corrected_scans, 2 * expected)
        cmp = self.compare(self.node_map(), self.saved("path_back.fgm"))
        self.assertGreaterEqual(cmp["agreement_in_either"], AGREEMENT, cmp)
        rospy.loginfo("corrected_path: agreement after moving back %.5f",
                      cmp["agreement_in_either"])


if __name__ == "__main__":
    rostest.rosrun("fragg_map", "map_server_correction", MapServerCorrectionTest)
