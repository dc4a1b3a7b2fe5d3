#!/usr/bin/env python3
"""The tier check (DESIGN §12): fails when a tier includes what it must not.

Tiers, lowest first: core <- planning <- ros.
  core      include/fragg_map/*.h, include/fragg_map/internal/, src/core/, cuda/
            knows no product: no planning, ROS, simulator, interop or geometry header, and no
            file of src/planning or src/ros; its public headers (include/fragg_map/*.h) name no
            CUDA runtime header and no cuda/ internal either.
  planning  include/fragg_map/planning/, src/planning/ (with its CUDA part src/planning/cuda/)
            knows no ROS; reads the map through its views, never the backend
            (internal/backend.h, the backends' headers); of the core's cuda/ folder its CUDA
            part includes the plain helpers only (ALLOWED_CUDA_HELPERS).
Usage: python3 scripts/check_tiers.py [REPO]   (exit 1 and one line a violation)
"""
import os
import re
import sys

ROOT = os.path.abspath(sys.argv[1] if len(sys.argv) > 1 else
                       os.path.join(os.path.dirname(__file__), ".."))
INCLUDE = re.compile(r'^\s*#\s*include\s*([<"])([^>"]+)[>"]')
SOURCE_EXT = (".h", ".hpp", ".cpp", ".cu", ".cuh")
ALLOWED_CUDA_HELPERS = {"cuda_check.h", "cuda_array.h", "cuda_stream.h"}
ROS_PREFIXES = ("ros/", "nodelet/", "sensor_msgs/", "nav_msgs/", "visualization_msgs/",
                "geometry_msgs/", "std_msgs/", "std_srvs/", "tf2", "rosbag/", "pcl_ros/",
                "pcl_conversions/", "octomap_msgs/", "dynamic_reconfigure/", "pluginlib/")
PRODUCT_PREFIXES = ("fragg_map/planning/", "fragg_map/ros/", "fragg_map/sim/",
                    "fragg_map/interop/", "fragg_map/geometry/", "fragg_map/store/")
BACKEND_HEADERS = ("fragg_map/internal/backend.h", "fragg_map/internal/cpu_backend.h",
                   "fragg_map/internal/cuda_backend_factory.h")


def files_under(rel, recursive=True):
    top = os.path.join(ROOT, rel)
    if not os.path.isdir(top):
        return []
    out = []
    for dirpath, dirnames, filenames in os.walk(top):
        for name in filenames:
            if name.endswith(SOURCE_EXT):
                out.append(os.path.join(dirpath, name))
        if not recursive:
            break
    return sorted(out)


def includes(path):
    with open(path, encoding="utf-8", errors="replace") as f:
        for number, line in enumerate(f, 1):
            m = INCLUDE.match(line)
            if m:
                yield number, m.group(1), m.group(2)


def resolves_into(path, name, folder):
    """Whether a quoted include `name` of `path` is a file of `folder` (relative to ROOT)."""
    candidate = os.path.normpath(os.path.join(os.path.dirname(path), name))
    return candidate.startswith(os.path.join(ROOT, folder) + os.sep) and os.path.exists(candidate)


def check_core(path, errors):
    public = os.path.dirname(path) == os.path.join(ROOT, "include", "fragg_map")
    cuda_names = set(os.listdir(os.path.join(ROOT, "cuda")))
    for number, kind, name in includes(path):
        why = None
        if name.startswith(PRODUCT_PREFIXES):
            why = "a product's header in the core"
        elif name.startswith(ROS_PREFIXES):
            why = "a ROS header in the core"
        elif kind == '"' and (resolves_into(path, name, "src/planning") or
                              resolves_into(path, name, "src/ros")):
            why = "a planning or ROS source in the core"
        elif public and (name.startswith("cuda") or (kind == '"' and name in cuda_names)):
            why = "a CUDA header in a public core header"
        if why:
            errors.append(f"{os.path.relpath(path, ROOT)}:{number}: {why}: {name}")


def check_planning(path, errors):
    in_cuda_part = os.path.join(ROOT, "src", "planning", "cuda") in path
    cuda_names = set(os.listdir(os.path.join(ROOT, "cuda")))
    for number, kind, name in includes(path):
        why = None
        if name.startswith("fragg_map/ros/") or name.startswith(ROS_PREFIXES):
            why = "a ROS header in planning"
        elif kind == '"' and resolves_into(path, name, "src/ros"):
            why = "a ROS source in planning"
        elif name in BACKEND_HEADERS:
            why = "a backend header in planning (read the map through its views)"
        elif kind == '"' and "/" not in name and name in cuda_names and \
                not os.path.exists(os.path.join(os.path.dirname(path), name)):
            if not in_cuda_part or name not in ALLOWED_CUDA_HELPERS:
                why = "a core CUDA internal in planning (allowed: " + \
                      ", ".join(sorted(ALLOWED_CUDA_HELPERS)) + ", in src/planning/cuda)"
        if why:
            errors.append(f"{os.path.relpath(path, ROOT)}:{number}: {why}: {name}")


def main():
    errors = []
    core = (files_under("include/fragg_map", recursive=False) +
            files_under("include/fragg_map/internal") + files_under("src/core") +
            files_under("cuda"))
    planning = files_under("include/fragg_map/planning") + files_under("src/planning")
    for path in core:
        check_core(path, errors)
    for path in planning:
        check_planning(path, errors)
    if not core or not planning:
        errors.append("check_tiers: found no core or planning sources under " + ROOT)
    for e in errors:
        print(e, file=sys.stderr)
    if errors:
        print(f"check_tiers: {len(errors)} include(s) cross a tier (DESIGN §12)", file=sys.stderr)
        return 1
    print(f"check_tiers: {len(core)} core and {len(planning)} planning files keep their tiers")
    return 0


if __name__ == "__main__":
    sys.exit(main())
