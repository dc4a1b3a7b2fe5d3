#!/usr/bin/env python3
"""Writes the fuzzers' seed corpora (test/fuzz/corpus/<target>/seed_*) from the real data in
../shared/data/real (a few dozen points of each file, so the corpus stays small) and from
`fragg_map` outputs (.fgm maps of every version, kept scans, spill files, `stats --scans`).
Files found by fuzzing (regressions, minimised finds) live beside the seeds under other names.

Usage: /usr/bin/python3 test/fuzz/make_seeds.py --fragg-map BUILD/bin/fragg_map
       [--real ../shared/data/real] [--out test/fuzz/corpus]
(/usr/bin/python3: the cloud_msg seeds are serialised with Debian's python3-sensor-msgs.)
"""
import argparse
import bz2
import io
import math
import os
import shutil
import struct
import subprocess
import tempfile
import zlib

N_POINTS = 48  # points kept of each real scan


def write(out, target, name, data, prefix="seed_"):
    """Writes test/fuzz/corpus/<target>/<prefix><name>. The corpus replay asserts that every
    seed_* input parses and every invalid_* input (a hand-made file the reader must refuse) is
    refused."""
    os.makedirs(os.path.join(out, target), exist_ok=True)
    with open(os.path.join(out, target, prefix + name), "wb") as f:
        f.write(data)


# ---------------------------------------------------------------- PCD
def pcd_header(text):
    """(header lines, data offset) of a PCD file."""
    lines, pos = [], 0
    while True:
        end = text.index(b"\n", pos)
        line = text[pos:end].decode("ascii").strip()
        lines.append(line)
        pos = end + 1
        if line.startswith("DATA"):
            return lines, pos


def lzf_decompress(src, out_len):
    out, i = bytearray(), 0
    while i < len(src):
        ctrl = src[i]
        i += 1
        if ctrl < 32:
            out += src[i:i + ctrl + 1]
            i += ctrl + 1
        else:
            length = ctrl >> 5
            if length == 7:
                length += src[i]
                i += 1
            ref = len(out) - ((ctrl & 0x1F) << 8) - src[i] - 1
            i += 1
            for _ in range(length + 2):
                out.append(out[ref])
                ref += 1
    assert len(out) == out_len
    return bytes(out)


def lzf_literals(data):
    """A valid LZF stream of literal runs only (no back references)."""
    out = bytearray()
    for i in range(0, len(data), 32):
        chunk = data[i:i + 32]
        out.append(len(chunk) - 1)
        out += chunk
    return bytes(out)


def with_fields(lines, **fields):
    out = []
    for line in lines:
        key = line.split(" ")[0]
        out.append(key + " " + fields[key] if key in fields else line)
    return ("\n".join(out) + "\n").encode("ascii")


def pcd_seeds(real, out):
    """Small PCDs from the real scans: binary, binary_compressed, ascii; returns xyz points."""
    points = []
    for folder in ("nebula_single_scans", "pcl_room_scans"):
        d = os.path.join(real, folder)
        for name in sorted(os.listdir(d)):
            if not name.endswith(".pcd"):
                continue
            raw = open(os.path.join(d, name), "rb").read()
            lines, start = pcd_header(raw)
            h = dict((l.split(" ")[0], l.split(" ")[1:]) for l in lines if l and l[0] != "#")
            sizes = [int(s) for s in h["SIZE"]]
            counts = [int(c) for c in h.get("COUNT", ["1"] * len(sizes))]
            step = sum(s * c for s, c in zip(sizes, counts))
            total = int(h["POINTS"][0])
            n = N_POINTS
            small = {"WIDTH": str(n), "HEIGHT": "1", "POINTS": str(n)}
            stem = name.split("_")[0]
            if h["DATA"][0] == "binary":
                body = raw[start:start + n * step]
                write(out, "pcd", stem + "_binary.pcd", with_fields(lines, **small) + body)
                if step == 12:
                    points += [struct.unpack_from("<3f", body, 12 * i) for i in range(n)]
            elif h["DATA"][0] == "binary_compressed":
                packed, unpacked = struct.unpack_from("<II", raw, start)
                soa = lzf_decompress(raw[start + 8:start + 8 + packed], unpacked)
                # Structure of arrays: each field's column, first n values of each.
                cols, pos = [], 0
                for s, c in zip(sizes, counts):
                    cols.append(soa[pos:pos + n * s * c])
                    pos += total * s * c
                data = b"".join(cols)
                lzf = lzf_literals(data)
                body = struct.pack("<II", len(lzf), len(data)) + lzf
                write(out, "pcd", stem + "_compressed.pcd", with_fields(lines, **small) + body)
    # ASCII, organised (4 x 3) and with a viewpoint, from the first points.
    pts = points[:12]
    ascii_lines = ["VERSION 0.7", "FIELDS x y z", "SIZE 4 4 4", "TYPE F F F", "COUNT 1 1 1",
                   "WIDTH 4", "HEIGHT 3", "VIEWPOINT 1 2 0.5 0.7071068 0 0 0.7071068",
                   "POINTS 12", "DATA ascii"]
    body = "".join("%.6f %.6f %.6f\n" % p for p in pts)
    write(out, "pcd", "organised_ascii.pcd", ("\n".join(ascii_lines) + "\n" + body).encode())
    # float64 fields and an extra count-3 field.
    d_lines = ["VERSION 0.7", "FIELDS x y z normal", "SIZE 8 8 8 4", "TYPE F F F F",
               "COUNT 1 1 1 3", "WIDTH 6", "HEIGHT 1", "POINTS 6", "DATA binary"]
    body = b"".join(struct.pack("<3d3f", *p, 0.0, 0.0, 1.0) for p in pts[:6])
    write(out, "pcd", "double_binary.pcd", ("\n".join(d_lines) + "\n").encode() + body)
    return points


# ---------------------------------------------------------------- PLY, xyz, KITTI .bin
def ply_seeds(real, out, points):
    raw = open(os.path.join(real, "small_gicp_pair", "source.ply"), "rb").read()
    end = raw.index(b"end_header\n") + len(b"end_header\n")
    header = raw[:end].decode("ascii").replace("element vertex 69792",
                                               "element vertex %d" % N_POINTS)
    write(out, "ply", "gicp_binary.ply", header.encode() + raw[end:end + 16 * N_POINTS])
    pts = points[:10]
    ascii_ply = ("ply\nformat ascii 1.0\nelement vertex %d\nproperty float x\nproperty float y\n"
                 "property float z\nelement face 1\nproperty list uchar int vertex_indices\n"
                 "end_header\n" % len(pts))
    ascii_ply += "".join("%.5f %.5f %.5f\n" % p for p in pts) + "3 0 1 2\n"
    write(out, "ply", "ascii_face.ply", ascii_ply.encode())
    be = ("ply\nformat binary_big_endian 1.0\nelement vertex %d\nproperty double x\n"
          "property double y\nproperty double z\nproperty uchar red\nend_header\n" % len(pts))
    write(out, "ply", "big_endian_double.ply",
          be.encode() + b"".join(struct.pack(">3dB", *p, 7) for p in pts))


def xyz_seeds(real, out, points):
    dat = bz2.decompress(open(os.path.join(real, "octomap", "scan.dat.bz2"), "rb").read())
    write(out, "xyz", "octomap_scan.dat", b"\n".join(dat.split(b"\n")[:40]) + b"\n")
    text = "# x y z\n" + "".join("%.4f %.4f %.4f\n" % p for p in points[:20])
    write(out, "xyz", "real_points.xyz", text.encode())
    write(out, "xyz", "commas_and_blank.xyz",
          ("\n".join("%g,%g,%g" % p for p in points[20:26]) + "\n\n1 2\n").encode(),
          prefix="invalid_")


def kitti_bin_seeds(out, points):
    write(out, "kitti_bin", "real_points.bin",
          b"".join(struct.pack("<4f", *p, 0.5) for p in points[:N_POINTS]))
    write(out, "kitti_bin", "one_point.bin", struct.pack("<4f", 1.0, 2.0, 3.0, 0.0))
    write(out, "kitti_bin", "partial_record.bin",
          struct.pack("<4f", 1.0, 2.0, 3.0, 0.0) + b"\0" * 7, prefix="invalid_")


# ---------------------------------------------------------------- insertion (fuzz_insert.cpp)
# The finite points that crashed or broke insertion once (issue 39): a huge coordinate with a
# tiny non-zero other one, denormals, the float range's ends.
EXTREME_POINTS = [
    (3.7e27, -4e-20, -3.7e27), (-3.7e27, 4e-20, 3.7e27), (4e-20, 3.7e27, -3.7e27),
    (3.4e38, 1e-30, -3.4e38), (1e30, 1e30, 1e30), (1e-45, 1e-45, 1e-45), (1e19, -1e-38, 1e19),
    (20, 1e-40, -20), (1e15, 1e15, -1e-25), (3e38, 3e38, 3e38)]


def insert_input(flags, res_index, max_range, points, pose=(0, 0, 0, 1, 0, 0, 0)):
    """One input of the insert target: flags, resolution index, max range, pose, points."""
    return (struct.pack("<BB", flags, res_index) + struct.pack("<f", 0.0) +
            struct.pack("<f", max_range) + struct.pack("<7f", *pose) +
            b"".join(struct.pack("<3f", *p) for p in points))


def insert_seeds(out, points):
    real = points[:16]
    for i, p in enumerate(EXTREME_POINTS):
        for res_index, res in ((1, "5cm"), (2, "20cm")):
            for max_range in (20.0, 80.0, -1.0):
                name = "extreme%d_%s_range%d" % (i, res, max(0, int(max_range)))
                write(out, "insert", name, insert_input(0, res_index, max_range, [p] + real))
    # Real points through every option: kept scans (insert, correct, remove), Bresenham, the
    # explicit models, an organised cloud with no-return clearing, a range noise, a turned and
    # moved sensor.
    pose = (1.5, -2.0, 0.7, 0.9238795, 0.0, 0.0, 0.3826834)
    write(out, "insert", "real_kept", insert_input(0x08, 1, 30.0, points[:N_POINTS], pose))
    write(out, "insert", "real_bresenham", insert_input(0x01, 2, -1.0, points[:N_POINTS]))
    write(out, "insert", "real_lidar", insert_input(0x02 | 0x20, 1, 10.0, points[:N_POINTS]))
    write(out, "insert", "real_pinhole", insert_input(0x04, 0, 5.0, points[:N_POINTS], pose))
    organised = list(points[:N_POINTS])
    organised[3] = (float("nan"),) * 3
    write(out, "insert", "real_organised", insert_input(0x10 | 0x40, 1, 8.0, organised))


# ---------------------------------------------------------------- ScanGraph
def pose6d(t, q):
    return struct.pack("<i3di4d", 3, *t, 4, *q)


def scan_graph_seeds(real, out):
    raw = open(os.path.join(real, "octomap", "spherical_scan.graph"), "rb").read()
    # The real file's first node, cut to a few points, as a one-node graph with one edge.
    (n_points,) = struct.unpack_from("<I", raw, 4)
    first = raw[8:8 + 28 * min(n_points, N_POINTS)]
    pose_at = 8 + 28 * n_points
    pose = raw[pose_at:pose_at + 4 + 24 + 4 + 32]
    node = struct.pack("<I", min(n_points, N_POINTS)) + first + pose + struct.pack("<I", 0)
    edge = struct.pack("<II", 0, 1) + pose6d((1, 0, 0), (1, 0, 0, 0)) + struct.pack("<d", 1.0)
    write(out, "scan_graph", "spherical_one_node.graph", struct.pack("<I", 1) + node +
          struct.pack("<I", 1) + edge)
    node2 = (struct.pack("<I", 2) + struct.pack("<i3d", 3, 1, 2, 3) +
             struct.pack("<i3d", 3, -1, 0.5, 2) + pose6d((0.5, 0, 0.2), (0.9238795, 0, 0, 0.3826834)) +
             struct.pack("<I", 1))
    write(out, "scan_graph", "two_nodes.graph", struct.pack("<I", 2) + node + node2 +
          struct.pack("<I", 0))
    write(out, "scan_graph", "empty.graph", struct.pack("<II", 0, 0))


# ---------------------------------------------------------------- pose files, waypoints, OBJ
def text_seeds(real, out, repo, fragg_map, scans_fgm):
    pose_txt = open(os.path.join(real, "slambook2_ch5_rgbd", "pose.txt"), "rb").read()
    write(out, "poses", "slambook_pose.txt", pose_txt)
    tum = "# timestamp tx ty tz qx qy qz qw\n" + "".join(
        "%.4f %s\n" % (1.0 + 0.1 * i, l) for i, l in enumerate(pose_txt.decode().splitlines()))
    write(out, "poses", "tum.txt", tum.encode())
    scans = subprocess.run([fragg_map, "stats", scans_fgm, "--scans"], check=True,
                           capture_output=True).stdout
    write(out, "poses", "stats_scans.txt", scans)
    write(out, "poses", "kitti_poses.txt",
          b"1 0 0 0.5 0 1 0 0 0 0 1 0\n1 0 0 1.0 0 1 0 0.1 0 0 1 0\n")
    write(out, "poses", "kitti_calib.txt",
          b"P0: 7 0 6 0 0 7 1 0 0 0 1 0\nTr: 0 -1 0 0 0 0 -1 0 1 0 0 -0.3\n")
    write(out, "poses", "matrix4.txt", open(os.path.join(
        real, "small_gicp_pair", "T_target_source.txt"), "rb").read())
    write(out, "poses", "kitti_times.txt", b"0.000000e+00\n1.036161e-01\n2.072319e-01\n")
    write(out, "waypoints", "path.txt",
          b"# x y z qx qy qz qw\n0 0 1 0 0 0 1\n\n1.5 0 1 0 0 0.7071068 0.7071068\n"
          b"3 -0.5 1.2 0 0 1 0\n")
    write(out, "waypoints", "one.txt", b"0.25 0.5 0.75 0 0 0 1")
    write(out, "waypoints", "bad_quaternion.txt", b"0 0 0 0 0 0 2\n", prefix="invalid_")
    write(out, "obj", "robot_box.obj", open(os.path.join(
        repo, "test", "rostest", "robot_box.obj"), "rb").read())
    write(out, "obj", "tetra_slashes.obj",
          b"# tetrahedron\no t\nv 0 0 0\nv 1 0 0\nv 0 1 0\nv 0 0 1\nvt 0 0\nvn 0 0 1\n"
          b"f 1/1/1 3/1/1 2/1/1\nf 1//1 2//1 4//1\nf 1 4 3\nf -3 -2 -1\n")
    write(out, "obj", "quad_fan.obj",
          b"v -1 -1 0\nv 1 -1 0\nv 1 1 0\nv -1 1 0\nv 0 0 1\nf 1 2 3 4\nf 1 2 5\nf 2 3 5\n"
          b"f 3 4 5\nf 4 1 5\n")


# ---------------------------------------------------------------- PointCloud2
def cloud_msg_seeds(out, points):
    from sensor_msgs.msg import PointCloud2, PointField

    def msg(fields, step, rows, width, height=1, big_endian=False):
        m = PointCloud2()
        m.header.frame_id = "velodyne"
        m.header.stamp.secs = 1673400472
        m.height, m.width = height, width
        m.fields = [PointField(name=n, offset=o, datatype=t, count=1) for n, o, t in fields]
        m.is_bigendian = big_endian
        m.point_step = step
        m.row_step = step * width
        m.data = b"".join(rows)
        m.is_dense = False
        buf = io.BytesIO()
        m.serialize(buf)
        return buf.getvalue()

    F32, F64, U16, U8 = PointField.FLOAT32, PointField.FLOAT64, PointField.UINT16, PointField.UINT8
    pts = points[:N_POINTS]
    xyz = [("x", 0, F32), ("y", 4, F32), ("z", 8, F32)]
    write(out, "cloud_msg", "packed_xyz",
          msg(xyz, 12, [struct.pack("<3f", *p) for p in pts], len(pts)))
    write(out, "cloud_msg", "xyzi_ring",
          msg(xyz + [("intensity", 12, F32), ("ring", 16, U16)], 18,
              [struct.pack("<4fH", *p, 9.0, i % 16) for i, p in enumerate(pts)], len(pts)))
    nan = float("nan")
    org = [struct.pack("<3f", *p) for p in pts[:10]] + [struct.pack("<3f", nan, nan, nan)] * 2
    write(out, "cloud_msg", "organised_nan", msg(xyz, 12, org, 4, height=3))
    write(out, "cloud_msg", "float64_reordered",
          msg([("z", 0, F64), ("x", 8, F64), ("y", 16, F64), ("flag", 24, U8)], 25,
              [struct.pack("<3dB", p[2], p[0], p[1], 1) for p in pts[:16]], 16))
    write(out, "cloud_msg", "big_endian",
          msg(xyz, 12, [struct.pack(">3f", *p) for p in pts[:8]], 8, big_endian=True))


# ---------------------------------------------------------------- .fgm and kept scans
def fgm_version(data):
    return struct.unpack_from("<I", data, 8)[0]


def fgm_blocks_end(data):
    """Offset of the byte after the block section of an .fgm (header is 88 bytes): per-block
    records up to version 4; version 5: u32 codec, u32 blocks per chunk, then per chunk a u32
    size and the packed chunk (block_chunks.h)."""
    (count,) = struct.unpack_from("<Q", data, 72)
    pos = 88
    if fgm_version(data) >= 5:
        _, per_chunk = struct.unpack_from("<II", data, pos)
        pos += 8
        for _ in range((count + per_chunk - 1) // per_chunk):
            (size,) = struct.unpack_from("<I", data, pos)
            pos += 4 + size
        return pos
    for _ in range(count):
        (size,) = struct.unpack_from("<I", data, pos + 12)
        pos += 16 + size
    return pos


def scan_record_end(data, pos, version):
    pos += 8 + 8 + 12 * 8 + 6 + 6 * 8 + 6 * 8
    if version >= 3:
        pos += 16
        (frame,) = struct.unpack_from("<H", data, pos)
        pos += 2 + frame
    pos += 8 + 4 + 4 + 8
    (packed,) = struct.unpack_from("<Q", data, pos)
    return pos + 8 + packed


def scan_v4_to_v2(rec):
    """A version 3/4 scan record without its range noise and frame id (version 2)."""
    fixed = 8 + 8 + 12 * 8 + 6 + 6 * 8 + 6 * 8
    (frame,) = struct.unpack_from("<H", rec, fixed + 16)
    return rec[:fixed] + rec[fixed + 16 + 2 + frame:]


def fgm_seeds(out, fragg_map, points, tmp):
    pcd = os.path.join(tmp, "cloud.pcd")
    lines = ["VERSION 0.7", "FIELDS x y z", "SIZE 4 4 4", "TYPE F F F", "COUNT 1 1 1",
             "WIDTH %d" % len(points), "HEIGHT 1", "VIEWPOINT 0 0 0 1 0 0 0",
             "POINTS %d" % len(points), "DATA binary"]
    with open(pcd, "wb") as f:
        f.write(("\n".join(lines) + "\n").encode() + b"".join(struct.pack("<3f", *p)
                                                              for p in points))
    maps = {}
    for name, args in (("plain", []), ("scans", ["--keep-scans"]),
                       ("scans_step", ["--keep-scans", "--scan-step", "0.01"])):
        path = os.path.join(tmp, name + ".fgm")
        subprocess.run([fragg_map, "build", pcd, "-o", path, "--resolution", "1.0",
                        "--max-range", "4", "--backend", "cpu"] + args, check=True,
                       capture_output=True)
        maps[name] = open(path, "rb").read()
    sub = os.path.join(tmp, "sub.fgm")
    subprocess.run([fragg_map, "truncate", os.path.join(tmp, "scans.fgm"), "--box", "-2", "-2",
                    "-2", "2", "2", "2", "-o", sub], check=True, capture_output=True)
    maps["region_box"] = open(sub, "rb").read()
    subprocess.run([fragg_map, "truncate", os.path.join(tmp, "plain.fgm"), "--center", "0", "0",
                    "0", "--radius", "2", "-o", sub], check=True, capture_output=True)
    maps["region_sphere"] = open(sub, "rb").read()

    def body(data, version):  # without the CRC footer (the fuzz target appends it)
        return data[:8] + struct.pack("<I", version) + data[12:-4]

    native = fgm_version(maps["plain"])
    for name, data in maps.items():
        write(out, "fgm", "%s_v%d.fgm" % (name, native), data[:-4])
    if native >= 5:
        zlib_seed = v5_with_zlib_chunks(maps["scans"])
        if zlib_seed:
            write(out, "fgm", "scans_v5_zlib.fgm", zlib_seed[:-4])
        # The older versions are derived from a per-block (version <= 4) writer's output: a
        # version 5 writer's chunks cannot be relabelled, so the committed v1-v4 seeds stay.
        print("make_seeds: fragg_map writes version %d: v1-v4 .fgm seeds left as they are"
              % native)
    else:
        derive_old_fgm_seeds(out, maps, body)
    # Kept-scan records (target `scan`: byte 0 = version - 2, bit 7 = spill file); the record
    # layout is the same in versions 4 and 5.
    for name in ("scans", "scans_step"):
        data = maps[name]
        pos = fgm_blocks_end(data) + 16
        rec = data[pos:scan_record_end(data, pos, 4)]
        write(out, "scan", name + "_v4", bytes([2]) + rec)
        write(out, "scan", name + "_v3", bytes([1]) + rec)
        write(out, "scan", name + "_v2", bytes([0]) + scan_v4_to_v2(rec))
        write(out, "scan", name + "_spill", bytes([0x82]) + b"FRAGGSCN" + rec)
    return os.path.join(tmp, "scans.fgm")


def v5_with_zlib_chunks(data):
    """A version 5 map whose zstd chunks (codec 2) are re-packed with zlib (codec 1), so that
    both chunk codecs are fuzzed; None without the `zstd` tool or for another codec."""
    (count,) = struct.unpack_from("<Q", data, 72)
    codec, per_chunk = struct.unpack_from("<II", data, 88)
    if codec != 2 or not shutil.which("zstd"):
        return None
    out, pos = bytearray(data[:88]) + struct.pack("<II", 1, per_chunk), 96
    for _ in range((count + per_chunk - 1) // per_chunk):
        (size,) = struct.unpack_from("<I", data, pos)
        raw = subprocess.run(["zstd", "-d", "-c"], input=data[pos + 4:pos + 4 + size],
                             capture_output=True, check=True).stdout
        packed = zlib.compress(raw, 6)
        out += struct.pack("<I", len(packed)) + packed
        pos += 4 + size
    body = bytes(out) + data[pos:-4]
    return body + struct.pack("<I", zlib.crc32(body))


def derive_old_fgm_seeds(out, maps, body):
    """Versions 1 to 4 of the maps of a version 4 writer (same block records)."""
    for name, data in maps.items():
        write(out, "fgm", name + "_v4.fgm", body(data, 4))
    write(out, "fgm", "plain_v1.fgm", body(maps["plain"], 1))
    write(out, "fgm", "scans_v3.fgm", body(maps["scans"], 3))
    # Version 2: the scan records without range noise and frame id.
    data = maps["scans"]
    pos = fgm_blocks_end(data) + 16
    v2 = bytearray(data[:pos])
    (kept,) = struct.unpack_from("<Q", data, pos - 8)
    for _ in range(kept):
        end = scan_record_end(data, pos, 4)
        v2 += scan_v4_to_v2(data[pos:end])
        pos = end
    write(out, "fgm", "scans_v2.fgm", body(bytes(v2) + b"\0\0\0\0", 2))


def main():
    here = os.path.dirname(os.path.abspath(__file__))
    repo = os.path.dirname(os.path.dirname(here))
    ap = argparse.ArgumentParser()
    ap.add_argument("--fragg-map", required=True)
    ap.add_argument("--real", default=os.path.join(repo, "..", "shared", "data", "real"))
    ap.add_argument("--out", default=os.path.join(here, "corpus"))
    a = ap.parse_args()
    with tempfile.TemporaryDirectory() as tmp:
        points = pcd_seeds(a.real, a.out)
        finite = [p for p in points if all(math.isfinite(v) for v in p)]
        ply_seeds(a.real, a.out, finite)
        xyz_seeds(a.real, a.out, finite)
        kitti_bin_seeds(a.out, finite)
        scan_graph_seeds(a.real, a.out)
        scans_fgm = fgm_seeds(a.out, a.fragg_map, finite[:N_POINTS], tmp)
        text_seeds(a.real, a.out, repo, a.fragg_map, scans_fgm)
        cloud_msg_seeds(a.out, finite)
        insert_seeds(a.out, finite)


if __name__ == "__main__":
    main()
