#!/usr/bin/python3
"""rostest of ~check_collision, ~truncate and ~merge on the smoke bag, after the bag checks
(tests 1-3).

Collision (test_5): every answer of the service equals `fragg_map collide` (the CLI, the same
core) on the map saved through ~save_map, for the same poses in the map frame: spheres at the
sensor positions (free), small boxes on occupied cells (the node's occupied_cells cloud:
colliding), random boxes over the map with random rotations (colliding cells counted), the
same boxes with unknown_is_occupied and a margin, boxes given in base_link (tf) at the scans'
stamps, the configured robot mesh (collision/mesh, an OBJ in centimetres at mesh_scale 0.01)
and a mesh sent in the request, and a path from a sensor position through a wall to a free pose
behind it (both ends free, the path collides on segment 0 inside the wall). Bad arguments
(no poses, NaN, a quaternion of norm 2, a zero-size box, an unknown shape, a mesh naming a
missing vertex, an unknown frame, poses and path together) answer success=false. The
`collisions` markers show the last check.

Sub-maps (test_6): the far half of the map (cell centres beyond the middle of its x extent)
is truncated into a file and removed: the file holds exactly those cells, the map exactly the
others, the markers and projected_map lose them; bad truncate and merge requests change
nothing; merging the file back (overwrite) gives the map saved before, cell for cell (hits and
log-odds of every block read from the .fgm files, and `fragg_map compare`). A copy (keep) of
the cells outside a sphere holds what `fragg_map truncate` cuts from the saved map and leaves
the map as it is.

The node maps with sensor_model/max_range 12 m (the CLI builds with --max-range 12) to keep the
map at about 5 M cells, so that the test stays well within its time on 2 cores."""
import json
import math
import os
import random
import subprocess
import time

import rospy
import rostest
from geometry_msgs.msg import Point, Pose, PoseStamped
from nav_msgs.msg import OccupancyGrid, Path
from sensor_msgs import point_cloud2
from sensor_msgs.msg import PointCloud2
from shape_msgs.msg import Mesh, MeshTriangle
from visualization_msgs.msg import Marker, MarkerArray

from fragg_map.srv import CheckCollision, CheckCollisionRequest, Merge, Truncate, TruncateRequest
from fgm_cells import BLOCK_EDGE, observed_cells, read_blocks
from map_server_checks import NS, MapServerBagChecks, wait_for
from map_server_correction_test import compose, read_bag

IDENTITY_Q = (0.0, 0.0, 0.0, 1.0)


def random_unit_quaternion(rng):
    while True:
        q = [rng.gauss(0.0, 1.0) for _ in range(4)]
        n = math.sqrt(sum(x * x for x in q))
        if n > 1e-3:
            return tuple(x / n for x in q)


def pose_msg(T, frame="map", stamp=None):
    ps = PoseStamped()
    ps.header.frame_id = frame
    if stamp is not None:
        ps.header.stamp = stamp
    ps.pose.position.x, ps.pose.position.y, ps.pose.position.z = T[0]
    q = ps.pose.orientation
    q.x, q.y, q.z, q.w = T[1]
    return ps


def cube_mesh(edge_m):
    """A closed cube centred on the origin, as a shape_msgs/Mesh and as OBJ text."""
    m = Mesh()
    verts = [((-0.5 if i & 1 == 0 else 0.5) * edge_m, (-0.5 if i & 2 == 0 else 0.5) * edge_m,
              (-0.5 if i & 4 == 0 else 0.5) * edge_m) for i in range(8)]
    for v in verts:
        m.vertices.append(Point(*v))
    faces = [(0, 2, 3, 1), (4, 5, 7, 6), (0, 1, 5, 4), (2, 6, 7, 3), (0, 4, 6, 2), (1, 3, 7, 5)]
    tris = []
    for a, b, c, d in faces:
        tris += [(a, b, c), (a, c, d)]
    for t in tris:
        m.triangles.append(MeshTriangle(vertex_indices=list(t)))
    obj = "".join("v %r %r %r\n" % v for v in verts)
    obj += "".join("f %d %d %d\n" % (a + 1, b + 1, c + 1) for a, b, c in tris)
    return m, obj


class MapServerServicesTest(MapServerBagChecks):
    @classmethod
    def setUpClass(cls):
        super().setUpClass()
        for name in ("check_collision", "truncate", "merge"):
            rospy.wait_for_service(NS + name, timeout=60)
        cls.check = rospy.ServiceProxy(NS + "check_collision", CheckCollision)
        cls.truncate = rospy.ServiceProxy(NS + "truncate", Truncate)
        cls.merge = rospy.ServiceProxy(NS + "merge", Merge)
        cls.collision_arrays, cls.grids, cls.clouds = [], [], []
        rospy.Subscriber("/collisions", MarkerArray, cls.collision_arrays.append, queue_size=10)
        rospy.Subscriber("/projected_map", OccupancyGrid, cls.grids.append, queue_size=10)
        rospy.Subscriber("/occupied_cells", PointCloud2, cls.clouds.append, queue_size=10)
        cls.stamps, base, T_base_lidar, _ = read_bag(rospy.get_param("~bag"),
                                                     rospy.get_param("~topic"))
        cls.T_map_base = base
        cls.sensor = [compose(T, T_base_lidar) for T in base]

    # --- helpers -------------------------------------------------------------------------
    def saved(self, name):
        path = os.path.join(self.tmp, name)
        res = self.save(path)
        self.assertTrue(res.success, res.message)
        return path

    def occupied_centres(self):
        wait_for(lambda: self.clouds, 10, "the occupied_cells cloud")
        return [tuple(p) for p in point_cloud2.read_points(self.clouds[-1], ("x", "y", "z"))]

    def cli_collide(self, map_path, poses, shape_args, *options):
        """`fragg_map collide` on poses ((x, y, z), (qx, qy, qz, qw)) in the map frame."""
        waypoints = os.path.join(self.tmp, "waypoints.txt")
        with open(waypoints, "w") as f:
            f.write("# x y z qx qy qz qw\n")
            for t, q in poses:
                f.write(" ".join(repr(float(v)) for v in tuple(t) + tuple(q)) + "\n")
        out = subprocess.run([self.cli, "collide", map_path, "--waypoints", waypoints, "--json",
                              "--backend", "cpu"] + shape_args + list(options),
                             check=True, stdout=subprocess.PIPE).stdout
        return json.loads(out)

    def call(self, poses=(), shape="box", dimensions=(), **kw):
        req = CheckCollisionRequest()
        req.poses = list(poses)
        req.shape = shape
        req.dimensions = list(dimensions)
        for k, v in kw.items():
            setattr(req, k, v)
        return self.check(req)

    def assert_same_answers(self, res, cli, what):
        self.assertTrue(res.success, "%s: %s" % (what, res.message))
        self.assertEqual(list(res.collides), cli["collides"], what)
        self.assertEqual(res.colliding, cli["colliding"], what)
        self.assertEqual(res.first_collision, cli["first_collision"], what)
        if "colliding_cells" in cli:
            self.assertEqual(list(res.colliding_cells), cli["colliding_cells"], what)
        if "path_collides" in cli:
            self.assertEqual(res.path_collides, cli["path_collides"], what)
            self.assertEqual(res.path_first_segment, cli["path_first_segment"], what)
            self.assertAlmostEqual(res.path_fraction, cli["path_fraction"], places=12, msg=what)
            self.assertEqual(res.path_poses_checked, cli["path_poses_checked"], what)

    # --- ~check_collision ----------------------------------------------------------------
    def test_5_check_collision_agrees_with_the_cli(self):
        map_path = self.saved("collide.fgm")
        checks_before = self.stats().collision_checks
        resolution = float(rospy.get_param(NS + "resolution"))
        rng = random.Random(15)

        # Spheres at the sensor positions: free space.
        free = [(T[0], IDENTITY_Q) for T in self.sensor]
        res = self.call([pose_msg(T) for T in free], "sphere", [0.3])
        self.assert_same_answers(res, self.cli_collide(map_path, free, ["--sphere", "0.3"]),
                                 "spheres at the sensor")
        self.assertEqual(res.colliding, 0, "the sensor positions are free")

        # Small boxes on occupied cells: every one collides.
        centres = self.occupied_centres()
        self.assertGreater(len(centres), 1000)
        on_cells = [(c, random_unit_quaternion(rng)) for c in rng.sample(centres, 40)]
        box = [0.5 * resolution] * 3
        res = self.call([pose_msg(T) for T in on_cells], "box", box)
        self.assert_same_answers(
            res, self.cli_collide(map_path, on_cells, ["--box"] + [repr(v) for v in box]),
            "boxes on occupied cells")
        self.assertEqual(res.colliding, len(on_cells))
        self.assertEqual(res.first_collision, 0)
        first = on_cells[0][0]
        self.assertLess(max(abs(a - b) for a, b in zip(
            (res.first_cell.x, res.first_cell.y, res.first_cell.z), first)), resolution,
            "first_cell is the occupied cell under pose 0")

        # Random robot-sized boxes over the map, with counts, then unknown as occupied + margin.
        lo = [min(c[i] for c in centres) for i in range(3)]
        hi = [max(c[i] for c in centres) for i in range(3)]
        spread = [(tuple(rng.uniform(lo[i], hi[i]) for i in range(3)),
                   random_unit_quaternion(rng)) for _ in range(300)]
        robot = [0.6, 0.4, 0.3]
        robot_args = ["--box"] + [repr(v) for v in robot]
        res = self.call([pose_msg(T) for T in spread], "box", robot, count_cells=True)
        cli = self.cli_collide(map_path, spread, robot_args, "--count-cells")
        self.assert_same_answers(res, cli, "random boxes")
        rospy.loginfo("random boxes: %d of %d collide, %d cells, %.2f ms (CLI %.2f ms)",
                      res.colliding, len(spread), sum(res.colliding_cells), res.ms, cli["ms"])
        self.assertGreater(res.colliding, 0)
        self.assertLess(res.colliding, len(spread))
        res = self.call([pose_msg(T) for T in spread], "box", robot, override_options=True,
                        unknown_is_occupied=True, margin=0.1)
        cli_unknown = self.cli_collide(map_path, spread, robot_args, "--unknown-occupied",
                                       "--margin", "0.1")
        self.assert_same_answers(res, cli_unknown, "random boxes, unknown occupied, margin")
        rospy.loginfo("random boxes, unknown occupied, margin 0.1: %d collide", res.colliding)
        self.assertGreater(res.colliding, cli["colliding"])

        # Poses given in base_link at the scans' stamps: tf puts them where the CLI puts the
        # composed poses.
        offset = ((0.8, 0.0, 0.2), IDENTITY_Q)
        in_base = [pose_msg(offset, "base_link", s) for s in self.stamps]
        in_map = [compose(T, offset) for T in self.T_map_base]
        res = self.call(in_base, "capsule", [0.2, 0.5])
        self.assert_same_answers(res, self.cli_collide(map_path, in_map, ["--capsule", "0.2",
                                                                          "0.5"]),
                                 "capsules through tf")

        # The configured robot mesh (centimetres, scale 0.01), and a mesh in the request.
        mixed = free + on_cells[:10] + spread[:50]
        res = self.call([pose_msg(T) for T in mixed], "mesh")
        self.assert_same_answers(
            res, self.cli_collide(map_path, mixed, ["--mesh", rospy.get_param("~robot_mesh"),
                                                    "--mesh-scale", "0.01"]),
            "configured mesh")
        self.assertGreater(res.colliding, 9)
        cube, obj = cube_mesh(0.45)
        obj_path = os.path.join(self.tmp, "cube.obj")
        with open(obj_path, "w") as f:
            f.write(obj)
        res = self.call([pose_msg(T) for T in mixed], "mesh", mesh=cube)
        self.assert_same_answers(res, self.cli_collide(map_path, mixed, ["--mesh", obj_path]),
                                 "request mesh")

        # Markers of the last check: one shape per pose, colliding ones red.
        wait_for(lambda: any(sum(1 for m in a.markers if m.ns == "colliding") == res.colliding
                             and sum(1 for m in a.markers if m.ns == "free") ==
                             len(mixed) - res.colliding
                             for a in self.collision_arrays[-1:]), 10, "collision markers")
        last = self.collision_arrays[-1]
        self.assertEqual(last.markers[0].action, Marker.DELETEALL)
        for m in last.markers:
            if m.ns == "colliding":
                self.assertEqual(m.type, Marker.TRIANGLE_LIST)
                self.assertEqual(len(m.points), 36)
                self.assertGreater(m.color.r, 0.9)

        # A path from a sensor position through a wall to a free pose behind it.
        self.check_path_through_a_wall(map_path, centres, rng)

        self.assertGreaterEqual(self.stats().collision_checks, checks_before + 8)

    def check_path_through_a_wall(self, map_path, centres, rng):
        start = self.sensor[0][0]
        # Occupied cells at the sensor's height (walls, trunks; not the ground), 4-12 m away.
        candidates = [c for c in centres
                      if 4.0 < math.dist(c, start) < 12.0 and abs(c[2] - start[2]) < 0.3]
        rng.shuffle(candidates)
        self.assertTrue(candidates)
        ball = ["--sphere", "0.1"]
        for wall in candidates[:50]:
            d = [(w - s) / math.dist(wall, start) for w, s in zip(wall, start)]
            behind = tuple(w + 1.0 * x for w, x in zip(wall, d))
            ends = [(start, IDENTITY_Q), (behind, IDENTITY_Q)]
            res = self.call([pose_msg(T) for T in ends], "sphere", [0.1], path_mode=True)
            self.assertTrue(res.success, res.message)
            if res.colliding:
                continue  # the pose behind is not free: another wall cell
            self.assert_same_answers(res, self.cli_collide(map_path, ends, ball, "--path"),
                                     "path through a wall")
            self.assertTrue(res.path_collides, "the path crosses occupied cell %s" % (wall,))
            self.assertEqual(res.path_first_segment, 0)
            total = math.dist(start, behind)
            self.assertGreater(res.path_fraction, 0.0)
            self.assertLessEqual(res.path_fraction * total, math.dist(start, wall) + 0.2)
            self.assertGreater(res.path_poses_checked, 2)
            rospy.loginfo("path through the wall at %s: segment %d, fraction %.4f of %.2f m, %d "
                          "poses checked", wall, res.path_first_segment, res.path_fraction, total,
                          res.path_poses_checked)
            # The same path as a nav_msgs/Path.
            path = Path()
            path.header.frame_id = "map"
            path.poses = [pose_msg(T, "") for T in ends]
            res_path = self.check(CheckCollisionRequest(path=path, shape="sphere",
                                                        dimensions=[0.1], path_mode=True))
            self.assertTrue(res_path.success, res_path.message)
            self.assertEqual(res_path.path_first_segment, res.path_first_segment)
            self.assertEqual(res_path.path_fraction, res.path_fraction)
            return
        self.fail("no occupied cell with free space behind it among 50 candidates")

    def test_5b_bad_collision_requests_are_refused(self):
        known = self.stats().known_voxels
        good = pose_msg(((0.0, 0.0, 1.0), IDENTITY_Q))
        nan = pose_msg(((math.nan, 0.0, 1.0), IDENTITY_Q))
        long_q = pose_msg(((0.0, 0.0, 1.0), (0.0, 0.0, 0.0, 2.0)))
        elsewhere = pose_msg(((0.0, 0.0, 1.0), IDENTITY_Q), "nowhere")
        broken, _ = cube_mesh(1.0)
        broken.triangles[2].vertex_indices[1] = 99
        path = Path()
        path.header.frame_id = "map"
        path.poses = [good]
        for kw, why, says in [
            (dict(shape="box", dimensions=[1, 1, 1]), "no poses", "no poses"),
            (dict(poses=[nan], shape="box", dimensions=[1, 1, 1]), "a NaN position", "pose 0"),
            (dict(poses=[good, long_q], shape="box", dimensions=[1, 1, 1]),
             "a quaternion of norm 2", "pose 1"),
            (dict(poses=[good], shape="box", dimensions=[1, 0, 1]), "a zero-size box", "box"),
            (dict(poses=[good], shape="cone", dimensions=[1]), "an unknown shape", "cone"),
            (dict(poses=[good], shape="mesh", mesh=broken), "a mesh naming a missing vertex",
             "mesh"),
            (dict(poses=[elsewhere], shape="sphere", dimensions=[0.2]), "an unknown frame",
             "nowhere"),
            (dict(poses=[good], path=path, shape="sphere", dimensions=[0.2]),
             "poses and path", "not both"),
            (dict(poses=[good], shape="sphere", dimensions=[0.2], override_options=True,
                  margin=-0.5), "a negative margin", "margin"),
        ]:
            res = self.check(CheckCollisionRequest(**kw))
            self.assertFalse(res.success, why)
            self.assertIn(says, res.message, why)
            self.assertEqual(len(res.collides), 0, why)
            self.assertEqual(res.first_collision, -1, why)
        self.assertEqual(self.stats().known_voxels, known)

    # --- ~truncate and ~merge ------------------------------------------------------------
    def shown_marker_points(self):
        """The occupied markers as the subscriber sees them after every array so far."""
        shown = {}
        for a in list(self.arrays):
            for m in a.markers:
                if m.action == Marker.DELETEALL:
                    shown.clear()
                elif m.action == Marker.DELETE:
                    shown.pop(m.id, None)
                else:
                    shown[m.id] = [(p.x, p.y, p.z) for p in m.points]
        return [p for pts in shown.values() for p in pts]

    def projected_occupied_xs(self, grid):
        info = grid.info
        xs = []
        for i, v in enumerate(grid.data):
            if v == 100:
                xs.append(info.origin.position.x + (i % info.width + 0.5) * info.resolution)
        return xs

    def test_6_truncate_far_half_and_merge_back(self):
        before_path = self.saved("before_truncate.fgm")
        before, resolution = read_blocks(before_path)
        known = observed_cells(before)
        self.assertEqual(self.stats().known_voxels, known)
        # The far half: the blocks beyond the middle of the x extent. The cut runs 1 mm past a
        # block face, so every block lies wholly on one side (cells go by their centres).
        edge = BLOCK_EDGE * resolution
        bxs = sorted(k[0] for k in before)
        k_mid = (bxs[0] + bxs[-1] + 1) // 2
        mid = k_mid * edge + 0.001
        far = {k: v for k, v in before.items() if k[0] >= k_mid}
        near = {k: v for k, v in before.items() if k[0] < k_mid}
        far_cells = observed_cells(far)
        self.assertGreater(far_cells, 10000)
        self.assertGreater(known - far_cells, 10000)
        big = 1.0e4
        box = dict(region=TruncateRequest.BOX, min=Point(mid, -big, -big), max=Point(big, big, big))
        sub_path = os.path.join(self.tmp, "far_half.fgm")

        # Bad requests: nothing changes, no file appears.
        for kw, why in [
            (dict(box, path="../far_half.fgm"), "'..' out of file_root"),
            (dict(box, path="/var/far_half.fgm"), "an absolute path outside file_root"),
            (dict(box, path=os.path.join(self.tmp, "far_half.bt")), "a .bt path"),
            (dict(box, path=""), "no path"),
            (dict(box, path=os.path.join(self.tmp, "no_such_dir", "far.fgm")), "a missing folder"),
            (dict(region=TruncateRequest.BOX, min=Point(1, 0, 0), max=Point(0, 1, 1),
                  path=sub_path), "an inverted box"),
            (dict(region=TruncateRequest.BOX, min=Point(math.nan, 0, 0), max=Point(1, 1, 1),
                  path=sub_path), "a NaN corner"),
            (dict(region=TruncateRequest.OUTSIDE_SPHERE, center=Point(0, 0, 0),
                  radius=math.nan, path=sub_path), "a NaN radius"),
            (dict(region=7, path=sub_path), "an unknown region"),
        ]:
            res = self.truncate(**kw)
            self.assertFalse(res.success, why)
            self.assertTrue(res.message, why)
            if "file_root" in why:
                self.assertIn("file_root", res.message)
        self.assertFalse(os.path.exists(sub_path))
        self.assertFalse(os.path.exists("/far_half.fgm"))
        self.assertFalse(os.path.exists("/var/far_half.fgm"))
        self.assertFalse(os.path.exists(os.path.join(self.tmp, "far_half.bt")))
        self.assertEqual(self.stats().known_voxels, known)

        # A copy (keep) of the cells outside a sphere: the same cells as `fragg_map truncate`
        # cuts from the saved map, and the map keeps them.
        ball_path = os.path.join(self.tmp, "outside.fgm")
        c = self.sensor[0][0]
        # (A path relative to file_root.)
        file_root = rospy.get_param(NS + "file_root")
        res = self.truncate(region=TruncateRequest.OUTSIDE_SPHERE, center=Point(*c), radius=6.0,
                            path=os.path.relpath(ball_path, file_root), keep=True)
        self.assertTrue(res.success, res.message)
        cli_ball = os.path.join(self.tmp, "cli_outside.fgm")
        subprocess.run([self.cli, "truncate", before_path, "--center"] + [repr(v) for v in c] +
                       ["--radius", "6.0", "-o", cli_ball], check=True, stdout=subprocess.DEVNULL)
        outside = read_blocks(ball_path)[0]
        self.assertEqual(outside, read_blocks(cli_ball)[0])
        self.assertEqual(res.cells, observed_cells(outside))
        self.assertGreater(res.cells, 1000)
        self.assertEqual(res.known_voxels, known)
        self.assertEqual(self.stats().known_voxels, known)

        # The far half out, into the file.
        arrays_before, grids_before = len(self.arrays), len(self.grids)
        res = self.truncate(path=sub_path, keep=False, **box)
        self.assertTrue(res.success, res.message)
        self.assertEqual(res.cells, far_cells)
        self.assertEqual(res.blocks, len(far))
        self.assertEqual(res.known_voxels, known - far_cells)
        self.assertEqual(self.stats().known_voxels, known - far_cells)
        rospy.loginfo("truncate: %d of %d cells in %d blocks moved out in %.1f ms", res.cells,
                      known, res.blocks, res.ms)
        self.assertTrue(read_blocks(sub_path)[0] == far, "the file holds the far half")
        self.assertTrue(read_blocks(self.saved("without_far_half.fgm"))[0] == near,
                        "the map holds the near half")
        # Markers and projected_map follow.
        wait_for(lambda: len(self.arrays) > arrays_before and len(self.grids) > grids_before, 20,
                 "markers and projected_map after ~truncate")
        shown = self.shown_marker_points()
        self.assertTrue(shown)
        self.assertLess(max(p[0] for p in shown), mid)
        self.assertLess(max(self.projected_occupied_xs(self.grids[-1])), mid + resolution)

        # Bad merges change nothing.
        for kw, why in [
            (dict(path="../far_half.fgm", mode="overwrite"), "'..' out of file_root"),
            (dict(path="/etc/far_half.fgm", mode="overwrite"), "an absolute path outside"),
            (dict(path=os.path.join(self.tmp, "missing.fgm"), mode="overwrite"), "no file"),
            (dict(path=sub_path, mode="sum"), "an unknown mode"),
            (dict(path=sub_path, mode="overwrite", use_transform=True, T_map_sub=Pose()),
             "a zero quaternion"),
        ]:
            res = self.merge(**kw)
            self.assertFalse(res.success, why)
            self.assertTrue(res.message, why)
        self.assertEqual(self.stats().known_voxels, known - far_cells)

        # Merged back: the map before, cell for cell.
        arrays_before = len(self.arrays)
        res = self.merge(path=sub_path, mode="overwrite")
        self.assertTrue(res.success, res.message)
        self.assertEqual(res.cells, far_cells)
        self.assertEqual(res.known_voxels, known)
        rospy.loginfo("merge: %d cells back in %.1f ms", res.cells, res.ms)
        after_path = self.saved("after_merge.fgm")
        after = read_blocks(after_path)[0]
        self.assertEqual(set(after), set(before))
        self.assertTrue(after == before, "%d blocks differ" %
                        sum(1 for k in before if after[k] != before[k]))
        cmp = self.compare(before_path, after_path)
        self.assertEqual(cmp["known_in_a"], cmp["known_in_b"])
        self.assertEqual(cmp["agreeing"], cmp["known_in_either"], cmp)
        wait_for(lambda: len(self.arrays) > arrays_before and
                 max(p[0] for p in self.shown_marker_points()) >= mid, 20,
                 "markers of the merged half")
        # Overwriting again through an identity T_map_sub (an exact key shift) changes nothing.
        identity = Pose()
        identity.orientation.w = 1.0
        res = self.merge(path=sub_path, mode="overwrite", use_transform=True, T_map_sub=identity)
        self.assertTrue(res.success, res.message)
        self.assertEqual(res.cells, far_cells)
        self.assertEqual(res.known_voxels, known)
        self.assertTrue(read_blocks(self.saved("after_second_merge.fgm"))[0] == before)


if __name__ == "__main__":
    rostest.rosrun("fragg_map", "map_server_services", MapServerServicesTest)
