#!/usr/bin/python3
"""Counts the test cases in a catkin test_results folder (gtest / rostest JUnit XML) and lists
the failed ones. Prints one line per failure, then a summary line:
"N test cases in F files: P passed, X failed, S skipped". Used by scripts/test.sh."""
import pathlib
import sys
import xml.etree.ElementTree as ET


def main(results_dir):
    files = sorted(pathlib.Path(results_dir).rglob("*.xml"))
    total = failed = skipped = 0
    for path in files:
        try:
            root = ET.parse(path).getroot()
        except ET.ParseError as e:
            print(f"unreadable result file {path}: {e}")
            failed += 1
            continue
        for case in root.iter("testcase"):
            total += 1
            name = f"{case.get('classname', '?')}.{case.get('name', '?')}"
            problem = case.find("failure")
            if problem is None:
                problem = case.find("error")
            if problem is not None:
                failed += 1
                message = (problem.get("message") or problem.text or "").strip()
                lines = [l.strip() for l in message.splitlines() if l.strip()]
                print(f"FAILED {name} ({path.name}): {' '.join(lines[:4])}")
            elif case.find("skipped") is not None or case.get("status") == "notrun":
                skipped += 1
    passed = total - failed - skipped
    print(f"{total} test cases in {len(files)} files: {passed} passed, {failed} failed, "
          f"{skipped} skipped")


if __name__ == "__main__":
    main(sys.argv[1] if len(sys.argv) > 1 else "build/test_results")
