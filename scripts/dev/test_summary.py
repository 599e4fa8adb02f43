#!/usr/bin/python3
"""One summary line of a ctest run (its JUnit file): passed, failed, skipped, and why each was skipped.

usage: test_summary.py CTEST_JUNIT.xml
"""
import collections
import sys
import xml.etree.ElementTree as ET


def skip_reason(output: str) -> str:
    lines = output.splitlines()
    for i, line in enumerate(lines):  # GoogleTest: "file:line: Skipped" then the message
        if line.rstrip().endswith(": Skipped") and i + 1 < len(lines) and lines[i + 1].strip():
            return lines[i + 1].strip()
    for line in lines:  # scripts (exit code 77) say why in a line of their own
        if "skip" in line.lower():
            return line.strip()
    return "no reason given"


def main() -> int:
    root = ET.parse(sys.argv[1]).getroot()
    counts = collections.Counter()
    reasons = collections.Counter()
    failed = []
    for case in root.iter("testcase"):
        status = case.get("status")
        if status == "run" and case.find("failure") is None:
            counts["passed"] += 1
        elif status == "notrun" or case.find("skipped") is not None:
            counts["skipped"] += 1
            reasons[skip_reason(case.findtext("system-out") or "")] += 1
        else:
            counts["failed"] += 1
            failed.append(case.get("name"))
    print(f"tests: {counts['passed']} passed, {counts['failed']} failed, {counts['skipped']} skipped")
    for name in failed:
        print(f"  failed: {name}")
    for reason, n in sorted(reasons.items()):
        print(f"  skipped ({n}): {reason}")
    return 0


if __name__ == "__main__":
    sys.exit(main())
