#!/usr/bin/python3
"""The soak's driver (scripts/soak.sh starts the master and the node, then this): feeds the
running map server a bag's clouds looped at a fixed rate with fresh stamps, calls its services
in turn, listens to its markers, samples its resident memory, and at the end checks its map.

Phases:
  mix   (most of the run): clouds looped at --rate_hz; every --call_every_s one service call,
        in turn: get_stats, save_map, load_map, clear_bbox, correct_poses, truncate (keep),
        merge, get_frontiers, check_collision, reset_map.
  drain: the mix's clouds still queued are inserted: waits until the last one sent shows in
        ~stats (published after each insertion with the cloud's stamp; the queue drops the
        oldest, never the newest), at most --drain_s.
  final: no service that changes the map; ~reset_map (repeated --final_reset_gap_s apart, at
        most --final_resets times, until one reading is within the reset bound below: a
        transient copy, such as the autosave thread's image of the map being written, is in
        one reading, a leak in every one), then each of the bag's clouds once (the
        next when the previous one shows in ~stats, so that the queue drops none; at most
        --cloud_s each), then ~save_map; the saved map must equal `fragg_map build` on the bag
        (cell for cell), checked only when the stats say no cloud of this phase was dropped.
Every wait is on the node's progress, bounded: a slow machine takes longer, never fails for it.

Writes into --out: rss.tsv (seconds, RSS MiB), map.tsv (the map's own host memory, blocks and
kept scans from ~stats), resets.tsv (seconds, RSS before and after each
~reset_map: the empty map's footprint over time), calls.tsv (service, success, ms),
summary.json (counts, checks). Exit status 1 when a check fails.
"""
import argparse
import json
import os
import re
import statistics
import subprocess
import sys
import threading
import time

import rosbag
import rospy
from geometry_msgs.msg import Point, Pose, PoseStamped
from sensor_msgs.msg import PointCloud2
from tf2_msgs.msg import TFMessage
from visualization_msgs.msg import MarkerArray

from fragg_map.msg import MapStats
from fragg_map.srv import (CheckCollision, CheckCollisionRequest, ClearBox, CorrectPoses,
                           GetFrontiers, GetFrontiersRequest, GetStats, LoadMap, Merge,
                           Reset, SaveMap, Truncate, TruncateRequest)

NS = "/fragg_map/"


def rss_mib(pid):
    with open("/proc/%d/status" % pid) as f:
        for line in f:
            if line.startswith("VmRSS:"):
                return int(line.split()[1]) / 1024.0
    return float("nan")


class Bag:
    """The bag's clouds, each with the transforms that place it (stamped as the cloud)."""

    def __init__(self, path, topic):
        self.clouds, self.tf, self.static = [], [], []
        with rosbag.Bag(path) as bag:
            for t, msg, _ in bag.read_messages(topics=[topic, "/tf", "/tf_static"]):
                if t == topic:
                    self.clouds.append(msg)
                elif t == "/tf":
                    self.tf.extend(msg.transforms)
                else:
                    self.static.extend(msg.transforms)
        if not self.clouds:
            sys.exit("soak: no %s clouds in %s" % (topic, path))
        self.placing = []  # per cloud: the /tf transforms with the cloud's stamp
        for c in self.clouds:
            self.placing.append([t for t in self.tf if t.header.stamp == c.header.stamp])
        self.frame = self.clouds[0].header.frame_id


class Counters:
    """Accumulates the node's drop counters across restarts (reset / load zero them)."""

    NAMES = ("dropped_queue_full", "dropped_no_tf", "dropped_tf_too_old", "rejected_clouds",
             "insertion_failures")

    def __init__(self):
        self.total = {n: 0 for n in self.NAMES}
        self.last = {n: 0 for n in self.NAMES}

    def add(self, stats):
        for n in self.NAMES:
            v = getattr(stats, n)
            self.total[n] += v - self.last[n] if v >= self.last[n] else v
            self.last[n] = v


class Soak:
    def __init__(self, args):
        self.args = args
        self.bag = Bag(args.bag, args.topic)
        self.lock = threading.Lock()  # service calls and stats, one at a time
        self.sent = 0
        self.sent_stamps = []  # (stamp, cloud index) of the recent clouds
        self.sent_set = set()  # every stamp sent (to count the inserted ones)
        self.inserted_stamps = set()  # stamps of sent clouds seen in ~stats: inserted
        self.stats_msgs = 0
        self.map_mem = []  # (s, map host MiB, blocks, kept scans) from ~stats, <= 1 per second
        self.markers = 0
        self.counters = Counters()
        self.calls = []  # (service, success, ms, message)
        self.rss = []  # (s, MiB)
        self.resets = []  # (s, RSS before, RSS after ~reset_map and its malloc_trim) [MiB]
        self.mix_resets = 0  # how many of them the mix called (the rest: the final phase's)
        self.publishing = True
        self.t0 = time.monotonic()
        self.pub = rospy.Publisher(args.topic, PointCloud2, queue_size=20)
        self.tf_pub = rospy.Publisher("/tf", TFMessage, queue_size=50)
        self.static_pub = rospy.Publisher("/tf_static", TFMessage, queue_size=1, latch=True)
        self.static_pub.publish(TFMessage(transforms=self.bag.static))
        rospy.Subscriber("/occupied_cells_vis_array", MarkerArray, self.on_markers,
                         queue_size=5)
        rospy.Subscriber(NS + "stats", MapStats, self.on_stats, queue_size=1000)
        for name in ("get_stats", "save_map", "load_map", "reset_map", "clear_bbox",
                     "correct_poses", "truncate", "merge", "get_frontiers", "check_collision"):
            rospy.wait_for_service(NS + name, timeout=60)
        self.srv = {
            "get_stats": rospy.ServiceProxy(NS + "get_stats", GetStats),
            "save_map": rospy.ServiceProxy(NS + "save_map", SaveMap),
            "load_map": rospy.ServiceProxy(NS + "load_map", LoadMap),
            "reset_map": rospy.ServiceProxy(NS + "reset_map", Reset),
            "clear_bbox": rospy.ServiceProxy(NS + "clear_bbox", ClearBox),
            "correct_poses": rospy.ServiceProxy(NS + "correct_poses", CorrectPoses),
            "truncate": rospy.ServiceProxy(NS + "truncate", Truncate),
            "merge": rospy.ServiceProxy(NS + "merge", Merge),
            "get_frontiers": rospy.ServiceProxy(NS + "get_frontiers", GetFrontiers),
            "check_collision": rospy.ServiceProxy(NS + "check_collision", CheckCollision),
        }

    def on_markers(self, _):
        self.markers += 1

    def on_stats(self, msg):
        """~stats comes after each insertion, stamped as the inserted cloud."""
        self.stats_msgs += 1
        t = self.elapsed()
        if not self.map_mem or t - self.map_mem[-1][0] >= 1.0:
            self.map_mem.append((t, msg.host_bytes / 1048576.0, msg.blocks, msg.scans_kept))
        ns = msg.header.stamp.to_nsec()
        if ns in self.sent_set:
            self.inserted_stamps.add(ns)

    def seen(self, stamp):
        return stamp.to_nsec() in self.inserted_stamps

    def elapsed(self):
        return time.monotonic() - self.t0

    # --- clouds -------------------------------------------------------------------------
    def publish(self, i):
        """Cloud i of the bag with its transforms, stamped now."""
        now = rospy.Time.now()
        transforms = []
        for t in self.bag.placing[i]:
            t.header.stamp = now
            transforms.append(t)
        self.tf_pub.publish(TFMessage(transforms=transforms))
        cloud = self.bag.clouds[i]
        cloud.header.stamp = now
        time.sleep(0.002)  # the transform first
        self.sent_set.add(now.to_nsec())
        self.pub.publish(cloud)
        self.sent += 1
        self.sent_stamps = (self.sent_stamps + [(now, i)])[-200:]
        return now

    def publish_loop(self):
        period = 1.0 / self.args.rate_hz
        next_t = time.monotonic()
        i = 0
        while self.publishing and not rospy.is_shutdown():
            self.publish(i)
            i = (i + 1) % len(self.bag.clouds)
            next_t += period
            time.sleep(max(0.0, next_t - time.monotonic()))

    # --- services -----------------------------------------------------------------------
    def call(self, name, *req):
        with self.lock:
            t = time.monotonic()
            try:
                res = self.srv[name](*req)
                ok, msg = res.success, res.message
            except rospy.ServiceException as e:
                res, ok, msg = None, False, str(e)
            ms = (time.monotonic() - t) * 1000.0
        self.calls.append((name, ok, ms, msg))
        return res

    def stats(self):
        res = self.call("get_stats")
        if res is None or not res.success:
            raise RuntimeError("get_stats failed")
        self.counters.add(res.stats)
        return res.stats

    def recent_stamp(self):
        """A stamp published 2-4 s ago (inserted and kept unless it was dropped)."""
        now = rospy.Time.now()
        for stamp, i in reversed(self.sent_stamps):
            if (now - stamp).to_sec() > 2.0:
                return stamp, i
        return None

    def one_call(self, k):
        out = self.args.out
        kind = k % 10
        if kind == 0:
            self.stats()
        elif kind == 1:
            self.call("save_map", os.path.join(out, "soak_saved.fgm"))
        elif kind == 2:
            if os.path.exists(os.path.join(out, "soak_saved.fgm")):
                self.stats()  # the drop counters before the load zeroes them
                self.call("load_map", os.path.join(out, "soak_saved.fgm"))
        elif kind == 3:
            self.call("clear_bbox", Point(0.5, 0.5, 0.0), Point(1.5, 1.5, 1.0))
        elif kind == 4:
            got = self.recent_stamp()
            if got:
                stamp, i = got
                tr = self.bag.placing[i][-1].transform
                pose = Pose()
                pose.position = Point(tr.translation.x + 0.02, tr.translation.y,
                                      tr.translation.z)
                pose.orientation = tr.rotation
                self.call("correct_poses", [stamp], [pose])
        elif kind == 5:
            req = TruncateRequest(region=TruncateRequest.BOX, min=Point(-2, -2, -1),
                                  max=Point(2, 2, 2), path=os.path.join(out, "soak_sub.fgm"),
                                  keep=True)
            self.call("truncate", req)
        elif kind == 6:
            if os.path.exists(os.path.join(out, "soak_sub.fgm")):
                self.call("merge", os.path.join(out, "soak_sub.fgm"), "overwrite", False, Pose())
        elif kind == 7:
            self.call("get_frontiers", GetFrontiersRequest(k=1))
        elif kind == 8:
            req = CheckCollisionRequest(shape="sphere", dimensions=[0.3])
            for x in range(5):
                p = PoseStamped()
                p.header.frame_id = self.args.frame
                p.pose.position = Point(x * 0.5, 0.0, 0.5)
                p.pose.orientation.w = 1.0
                req.poses.append(p)
            self.call("check_collision", req)
        else:
            self.stats()
            self.reset()

    def reset(self):
        """~reset_map; its answer gives the RSS before and after (the heap trimmed)."""
        res = self.call("reset_map")
        m = re.search(r"resident memory ([0-9.]+) -> ([0-9.]+) MiB", res.message if res else "")
        if m:
            self.resets.append((self.elapsed(), float(m.group(1)), float(m.group(2))))

    def note(self):
        """One progress line."""
        rss = self.rss[-1][1] if self.rss else float("nan")
        failed = sum(1 for c in self.calls if not c[1])
        print("soak: %6.0f s  sent %6d  RSS %7.1f MiB  calls %5d (%d failed)  dropped %s" %
              (self.elapsed(), self.sent, rss, len(self.calls), failed,
               self.counters.total), flush=True)

    # --- memory -------------------------------------------------------------------------
    def sample_loop(self):
        while self.sampling and not rospy.is_shutdown():
            try:
                mib = rss_mib(self.args.pid)
            except OSError:
                break
            self.rss.append((self.elapsed(), mib))
            time.sleep(self.args.sample_s)

    # --- run ----------------------------------------------------------------------------
    def wait_for(self, predicate, timeout_s):
        deadline = time.monotonic() + timeout_s
        while time.monotonic() < deadline:
            if predicate():
                return True
            time.sleep(0.2)
        return False

    def run(self):
        a = self.args
        self.sampling = True
        sampler = threading.Thread(target=self.sample_loop, daemon=True)
        sampler.start()
        publisher = threading.Thread(target=self.publish_loop, daemon=True)
        publisher.start()
        mix_end = self.t0 + a.seconds - a.final_s
        k = 0
        next_note = self.t0
        while time.monotonic() < mix_end and not rospy.is_shutdown():
            self.one_call(k)
            k += 1
            if time.monotonic() >= next_note:
                next_note += a.note_every_s
                self.note()
            time.sleep(a.call_every_s)
        self.note()
        self.publishing = False
        publisher.join()
        self.mix_sent = self.sent
        self.mix_s = self.elapsed()

        # The queue drains: the last cloud sent is inserted (or the bound passes).
        last = self.sent_stamps[-1][0] if self.sent_stamps else None
        self.drained = last is not None and self.wait_for(lambda: self.seen(last), a.drain_s)
        self.drain_s = self.elapsed() - self.mix_s
        print("soak: mix over at %.0f s, queue drained %s in %.1f s" %
              (self.mix_s, self.drained, self.drain_s), flush=True)

        # Final phase: nothing that changes the map but the clouds themselves.
        self.stats()
        self.mix_resets = len(self.resets)
        for attempt in range(max(1, a.final_resets)):
            if attempt:
                time.sleep(a.final_reset_gap_s)
            self.reset()
            if self.final_reset_within_bound() is not False:
                break
        before = self.stats()
        n = len(self.bag.clouds)
        inserted = True
        for i in range(n):  # each once the one before is in: the queue never drops one
            stamp = self.publish(i)
            if not self.wait_for(lambda: self.seen(stamp), a.cloud_s):
                inserted = False
                break
        after = self.stats()
        self.sampling = False
        sampler.join()
        final_saved = os.path.join(a.out, "soak_final.fgm")
        self.call("save_map", final_saved)
        return self.report(before, after, inserted, n, final_saved)

    def reset_rss_bound(self):
        """The bound on the RSS after a final-phase ~reset_map (MiB): --reset_rss_ratio x the
        lowest reading after a mix reset + --reset_rss_slack_mib; None without a mix reset."""
        mix = [r[2] for r in self.resets[:self.mix_resets]]
        if not mix:
            return None
        return self.args.reset_rss_ratio * min(mix) + self.args.reset_rss_slack_mib

    def final_reset_within_bound(self):
        """Whether the lowest final-phase reading is within the bound (None: no bound)."""
        bound = self.reset_rss_bound()
        final = [r[2] for r in self.resets[self.mix_resets:]]
        if bound is None or not final:
            return None
        return min(final) <= bound

    def report(self, before, after, inserted, n, final_saved):
        a = self.args
        s = {"seconds": round(self.elapsed(), 1), "rate_hz": a.rate_hz, "bag": a.bag,
             "mix_s": round(self.mix_s, 1), "drain_s": round(self.drain_s, 1),
             "clouds_sent": self.sent, "clouds_inserted": len(self.inserted_stamps),
             "stats_messages": self.stats_msgs, "marker_arrays": self.markers,
             "dropped": dict(self.counters.total)}
        calls = {}
        for name, ok, ms, _ in self.calls:
            c = calls.setdefault(name, {"calls": 0, "failed": 0, "ms_max": 0.0})
            c["calls"] += 1
            c["failed"] += 0 if ok else 1
            c["ms_max"] = round(max(c["ms_max"], ms), 1)
        s["calls"] = calls
        # Every cloud sent is inserted or counted dropped, but for those dropped between the
        # last ~get_stats and a ~reset_map / ~load_map (the counters restart there).
        s["clouds_unaccounted"] = (self.sent - len(self.inserted_stamps) -
                                   sum(self.counters.total.values()))
        if self.resets:
            s["rss_after_reset_mib"] = {"first": self.resets[0][2], "last": self.resets[-1][2],
                                        "min": min(r[2] for r in self.resets),
                                        "max": max(r[2] for r in self.resets),
                                        "resets": len(self.resets)}
        failed = [(n_, m) for n_, ok, _, m in self.calls if not ok]
        # correct_poses answers success with unknown stamps; a failure is a real one.
        s["failed_calls"] = failed[:20]

        # RSS: after the warm-up, the last third's median against the first third's. (Not the
        # peaks: a sample every 2 s catches a random overlap of transient copies of the map,
        # the autosave's and ~save_map's images, ~load_map's and ~merge's second map.) The
        # medians follow the map's size when the thirds are sampled: a fair leak bound over
        # thirds of minutes, not of 20 s (--rss_ratio 0 leaves it out; it is still reported).
        warm = max(a.warmup_s, 0.2 * (a.seconds - a.final_s))
        steady = [m for t, m in self.rss if t >= warm]
        third = len(steady) // 3
        checks = {}
        if third >= 2:
            first, last = steady[:third], steady[-third:]
            med_first, med_last = statistics.median(first), statistics.median(last)
            s["rss_mib"] = {"warmup_s": warm, "first_third_median": round(med_first, 1),
                            "last_third_median": round(med_last, 1),
                            "first_third_max": round(max(first), 1),
                            "last_third_max": round(max(last), 1),
                            "overall_max": round(max(m for _, m in self.rss), 1),
                            "samples": len(self.rss), "ratio_bound": a.rss_ratio}
            if a.rss_ratio > 0:
                checks["rss_bounded (last third median <= %.2f x first third median)" %
                       a.rss_ratio] = med_last <= a.rss_ratio * med_first
        elif a.rss_ratio > 0:
            checks["rss_bounded (enough samples)"] = False
        # RSS with an empty map: each ~reset_map reports it after the heap is trimmed, so
        # whatever the node still holds then (a leak of maps, clouds, messages, anything) is
        # in it, and the map's size is not. The final phase's resets (no call running, the
        # queue drained) against the lowest mix reset: a transient copy alive during one reset
        # (the autosave thread's image of a ~220 MiB map being written, a latched message not
        # yet replaced) moves single readings by up to ~250 MiB, so the lowest of the final
        # readings counts; a node keeping a map per cycle adds its ~220 MiB to every one.
        if a.reset_rss_ratio > 0:
            name = ("rss_after_reset_bounded (lowest after a final-phase ~reset_map <= %.2f x "
                    "the lowest after a mix one + %.0f MiB)" %
                    (a.reset_rss_ratio, a.reset_rss_slack_mib))
            within = self.final_reset_within_bound()
            if within is not None:
                s["rss_after_reset_mib"]["bound"] = round(self.reset_rss_bound(), 1)
                s["rss_after_reset_mib"]["final"] = [r[2] for r in self.resets[self.mix_resets:]]
                checks[name] = within
            else:
                checks[name + " (a mix reset and a final one)"] = False
        checks["drops by the queue only (no_tf = rejected = failures = 0)"] = all(
            v == 0 for k, v in self.counters.total.items()
            if k not in ("dropped_queue_full", "dropped_tf_too_old"))
        checks["no failed service call"] = not failed
        checks["the mix's queue drained (its last cloud inserted)"] = self.drained
        checks["markers received"] = self.markers > 0
        final_dropped = (after.dropped_queue_full - before.dropped_queue_full +
                         after.dropped_no_tf - before.dropped_no_tf)
        s["final_phase"] = {"clouds": n, "scans": after.scans, "dropped": final_dropped}
        if inserted and final_dropped == 0 and after.scans == n:
            built = os.path.join(a.out, "soak_cli.fgm")
            subprocess.run([a.cli, "build", a.bag, "-o", built, "--topic", a.topic, "--frame",
                            a.frame], check=True, stdout=subprocess.DEVNULL)
            cmp = json.loads(subprocess.run([a.cli, "compare", built, final_saved, "--json"],
                                            check=True, stdout=subprocess.PIPE).stdout)
            s["final_phase"]["compare"] = {"known_in_either": cmp["known_in_either"],
                                           "agreeing": cmp["agreeing"]}
            checks["final map == fragg_map build"] = (
                cmp["known_in_either"] > 0 and cmp["agreeing"] == cmp["known_in_either"])
        else:
            s["final_phase"]["compare"] = "skipped: clouds of the final phase were dropped"
        s["checks"] = checks
        with open(os.path.join(a.out, "rss.tsv"), "w") as f:
            f.write("# seconds\trss_mib\n")
            for t, m in self.rss:
                f.write("%.1f\t%.1f\n" % (t, m))
        with open(os.path.join(a.out, "map.tsv"), "w") as f:
            f.write("# seconds\tmap_host_mib\tblocks\tscans_kept (~stats after insertions)\n")
            for t, mib, blocks, kept in self.map_mem:
                f.write("%.1f\t%.1f\t%d\t%d\n" % (t, mib, blocks, kept))
        with open(os.path.join(a.out, "resets.tsv"), "w") as f:
            f.write("# seconds\trss_before_mib\trss_after_mib (~reset_map, heap trimmed)"
                    "\tphase\n")
            for i, (t, before_mib, after_mib) in enumerate(self.resets):
                f.write("%.1f\t%.1f\t%.1f\t%s\n" % (t, before_mib, after_mib,
                                                 "mix" if i < self.mix_resets else "final"))
        with open(os.path.join(a.out, "calls.tsv"), "w") as f:
            f.write("# service\tsuccess\tms\tmessage\n")
            for name, ok, ms, msg in self.calls:
                f.write("%s\t%d\t%.1f\t%s\n" % (name, ok, ms, msg.replace("\n", " ")[:200]))
        with open(os.path.join(a.out, "summary.json"), "w") as f:
            json.dump(s, f, indent=2)
        print(json.dumps(s, indent=2))
        return all(checks.values())


def main():
    p = argparse.ArgumentParser()
    p.add_argument("--bag", required=True)
    p.add_argument("--topic", default="/points")
    p.add_argument("--frame", default="map")
    p.add_argument("--pid", type=int, required=True, help="the node's process")
    p.add_argument("--cli", required=True, help="the fragg_map executable")
    p.add_argument("--out", required=True)
    p.add_argument("--seconds", type=float, default=120)
    p.add_argument("--final_s", type=float, default=10, help="time kept for the final phase")
    p.add_argument("--rate_hz", type=float, default=10)
    p.add_argument("--call_every_s", type=float, default=1.0)
    p.add_argument("--sample_s", type=float, default=2.0)
    p.add_argument("--drain_s", type=float, default=120,
                   help="bound on the wait for the mix's queued clouds")
    p.add_argument("--cloud_s", type=float, default=60,
                   help="bound on the wait for each cloud of the final phase")
    p.add_argument("--warmup_s", type=float, default=20)
    p.add_argument("--rss_ratio", type=float, default=1.1,
                   help="bound on the last third's RSS median over the first third's "
                   "(0: reported, not checked)")
    p.add_argument("--reset_rss_ratio", type=float, default=1.25,
                   help="bound on the lowest RSS after a final-phase ~reset_map over the lowest "
                   "after a mix one (0: not checked)")
    p.add_argument("--reset_rss_slack_mib", type=float, default=64)
    p.add_argument("--final_resets", type=int, default=3,
                   help="final-phase ~reset_map calls at most (until one is within the bound)")
    p.add_argument("--final_reset_gap_s", type=float, default=6.0,
                   help="between final-phase resets: longer than an autosave period (5 s)")
    p.add_argument("--note_every_s", type=float, default=30, help="progress lines")
    args = p.parse_args(rospy.myargv()[1:])
    rospy.init_node("fragg_map_soak", disable_signals=True)
    ok = Soak(args).run()
    sys.exit(0 if ok else 1)


if __name__ == "__main__":
    main()
