#!/usr/bin/python3
"""Counts the test cases in a catkin test_results folder (gtest / rostest JUnit XML), lists the
failed and the skipped ones and checks the required suites. Prints one line per failure and per
skip, one line per required suite, then a summary line:
"N test cases in F files: P passed, X failed, S skipped". Used by scripts/test.sh.

  test_counts.py RESULTS_DIR [--require 'NAME=GLOB' ...]

A required suite is the result files under RESULTS_DIR whose name matches GLOB (fnmatch); it
fails when no file matches, when its files hold no test case, or when any of its cases failed
or was skipped (a required suite whose data or library is missing must not pass as a skip).
Exit status: 1 when a required suite fails, else 0 (catkin_test_results gates the failures)."""
import argparse
import fnmatch
import pathlib
import sys
import xml.etree.ElementTree as ET


def case_verdicts(path):
    """[(name, 'passed' | 'failed' | 'skipped', message)] of one result file; None when the
    file cannot be read."""
    try:
        root = ET.parse(path).getroot()
    except ET.ParseError:
        return None
    verdicts = []
    for case in root.iter("testcase"):
        name = f"{case.get('classname', '?')}.{case.get('name', '?')}"
        problem = case.find("failure")
        if problem is None:
            problem = case.find("error")
        skip = case.find("skipped")
        if problem is not None:
            message = (problem.get("message") or problem.text or "").strip()
            verdicts.append((name, "failed", message))
        elif skip is not None or case.get("status") == "notrun":
            message = ((skip.get("message") or skip.text or "") if skip is not None else "").strip()
            verdicts.append((name, "skipped", message))
        else:
            verdicts.append((name, "passed", ""))
    return verdicts


def first_lines(message, n=4):
    return " ".join([l.strip() for l in message.splitlines() if l.strip()][:n])


def main():
    parser = argparse.ArgumentParser()
    parser.add_argument("results_dir", nargs="?", default="build/test_results")
    parser.add_argument("--require", action="append", default=[], metavar="NAME=GLOB")
    args = parser.parse_args()
    files = sorted(pathlib.Path(args.results_dir).rglob("*.xml"))
    total = failed = skipped = 0
    by_file = {}
    for path in files:
        verdicts = case_verdicts(path)
        if verdicts is None:
            print(f"unreadable result file {path}")
            failed += 1
            by_file[path] = [("?", "failed", "unreadable")]
            continue
        by_file[path] = verdicts
        for name, verdict, message in verdicts:
            total += 1
            if verdict == "failed":
                failed += 1
                print(f"FAILED {name} ({path.name}): {first_lines(message)}")
            elif verdict == "skipped":
                skipped += 1
                print(f"SKIPPED {name} ({path.name}): {first_lines(message, 2)}")
    missing = 0
    for spec in args.require:
        name, _, pattern = spec.partition("=")
        if not pattern:
            print(f"bad --require '{spec}': NAME=GLOB")
            missing += 1
            continue
        matched = [p for p in files if fnmatch.fnmatch(p.name, pattern)]
        verdicts = [v for p in matched for v in by_file[p]]
        counts = {k: sum(1 for v in verdicts if v[1] == k) for k in ("passed", "failed", "skipped")}
        if not matched or not verdicts or counts["failed"] or counts["skipped"]:
            missing += 1
            why = ("no result file" if not matched else
                   "no test case" if not verdicts else
                   f"{counts['failed']} failed, {counts['skipped']} skipped")
            print(f"REQUIRED SUITE FAILED: {name} ({pattern}): {why}")
        else:
            print(f"required suite {name}: {counts['passed']} passed in {len(matched)} files")
    passed = total - failed - skipped
    print(f"{total} test cases in {len(files)} files: {passed} passed, {failed} failed, "
          f"{skipped} skipped" + (f"; {missing} required suites failed" if missing else ""))
    return 1 if missing else 0


if __name__ == "__main__":
    sys.exit(main())
