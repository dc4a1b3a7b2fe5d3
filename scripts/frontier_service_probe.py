#!/usr/bin/python3
"""Times ~get_frontiers on a running map server as a user would (scripts/frontier_service_bench.sh
starts the master, the node and the bags): waits until the node holds --scans scans, then, for
each query (the whole map, then a box of --box-edge metres around the last sensor position),
calls ~get_frontiers with k viewpoints while another thread asks ~get_stats every 50 ms and a
second bag (--more-bag) is played into the node (from the first query on). Prints one JSON object: per query the client's
wall time, the node's own ms, frontier cells, clusters, the node's message, the slowest
~get_stats answer while it ran and the scans inserted meanwhile.

  frontier_service_probe.py --scans 10 --more-bag B.bag [--k 8] [--box-edge 40] [--box-height 6]
                            [--box-center X Y Z] [--ns /fragg_map]
"""
import argparse
import json
import subprocess
import threading
import time

import rospy
from fragg_map.srv import GetFrontiers, GetFrontiersRequest, GetStats
from geometry_msgs.msg import Point


def main():
    ap = argparse.ArgumentParser()
    ap.add_argument("--scans", type=int, required=True)
    ap.add_argument("--more-bag", required=True)
    ap.add_argument("--k", type=int, default=8)
    ap.add_argument("--box-edge", type=float, default=40.0)
    ap.add_argument("--box-height", type=float, default=6.0)
    ap.add_argument("--box-center", type=float, nargs=3, default=[0.0, 0.0, 0.0],
                    help="the box's centre (map frame, m): the last sensor position")
    ap.add_argument("--ns", default="/fragg_map")
    ap.add_argument("--timeout", type=float, default=900.0)
    ap.add_argument("--before-queries", default="", help="a shell command run before the queries")
    a = ap.parse_args()
    rospy.init_node("frontier_service_probe", anonymous=True)
    rospy.wait_for_service(a.ns + "/get_stats", timeout=120)
    rospy.wait_for_service(a.ns + "/get_frontiers", timeout=120)
    stats = rospy.ServiceProxy(a.ns + "/get_stats", GetStats)
    frontiers = rospy.ServiceProxy(a.ns + "/get_frontiers", GetFrontiers)

    deadline = time.monotonic() + a.timeout
    while stats().stats.scans < a.scans:
        if time.monotonic() > deadline:
            raise SystemExit("probe: the node never held %d scans" % a.scans)
        time.sleep(0.2)
    before = stats().stats
    if a.before_queries:  # e.g. stop the first bag's player (kept alive past its end)
        subprocess.run(a.before_queries, shell=True, check=False)
        time.sleep(1.0)
    out = {"scans": before.scans, "known_voxels": before.known_voxels, "queries": []}

    player = None
    c = a.box_center
    half, height = 0.5 * a.box_edge, 0.5 * a.box_height
    box = GetFrontiersRequest(k=a.k, use_box=True,
                              box_min=Point(c[0] - half, c[1] - half, c[2] - height),
                              box_max=Point(c[0] + half, c[1] + half, c[2] + height))
    box_name = "box %.0f x %.0f x %.0f m" % (a.box_edge, a.box_edge, a.box_height)
    # First on an idle node (the query's own time), then while the second bag is inserted
    # (the query waits for the scan being inserted, shares the cores, and ~get_stats is asked).
    for inserting in (False, True):
        for name, req in (("whole map", GetFrontiersRequest(k=a.k)), (box_name, box)):
            if inserting and player is None:
                player = subprocess.Popen(
                    ["rosbag", "play", "--clock", "-q", "--keep-alive", a.more_bag],
                    stdout=subprocess.DEVNULL, stderr=subprocess.DEVNULL)
                time.sleep(1.0)
            slowest = [0.0]
            running = threading.Event()
            running.set()

            def ask_stats():
                while running.is_set():
                    t0 = time.monotonic()
                    stats()
                    slowest[0] = max(slowest[0], time.monotonic() - t0)
                    time.sleep(0.05)

            scans_before = stats().stats.scans
            asker = threading.Thread(target=ask_stats)
            asker.start()
            t0 = time.monotonic()
            res = frontiers(req)
            wall = time.monotonic() - t0
            running.clear()
            asker.join()
            out["queries"].append({
                "query": name + (", while scans are inserted" if inserting else ", idle node"),
                "success": res.success, "client_s": round(wall, 4),
                "node_ms": round(res.ms, 1), "frontier_cells": res.frontier_cells,
                "clusters": len(res.clusters),
                "clusters_with_viewpoints": sum(1 for c in res.clusters if c.viewpoints),
                "message": res.message, "slowest_get_stats_s": round(slowest[0], 4),
                "scans_inserted_meanwhile": stats().stats.scans - scans_before})
    if player is not None:
        player.terminate()
        player.wait()
    after = stats().stats
    out["insertion_ms_mean"] = round(after.insertion_ms_mean, 1)
    out["insertion_ms_p99"] = round(after.insertion_ms_p99, 1)
    out["scans_at_end"] = after.scans
    print(json.dumps(out, indent=1))


if __name__ == "__main__":
    main()
