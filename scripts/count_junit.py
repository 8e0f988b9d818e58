#!/usr/bin/python3
"""Counts test cases in every JUnit XML file below a folder and prints 'N passed, N failed, N skipped'.

Each <testcase> element is counted once, whatever the nesting of <testsuites>/<testsuite> (gtest >= 1.10
writes both levels, which makes catkin_test_results double count). A file that does not parse counts as
one failure. Exit status 1 when anything failed or no test ran at all.
"""
import os
import sys
import xml.etree.ElementTree as ET


def classify(case):
    if case.find("failure") is not None or case.find("error") is not None:
        return "failed"
    if case.find("skipped") is not None or case.get("status") in ("notrun", "disabled"):
        return "skipped"
    if case.get("status") == "fail":
        return "failed"
    return "passed"


def failure_reason(case):
    """The first lines of a failed case's message, so that a log's tail says why."""
    for tag in ("failure", "error"):
        element = case.find(tag)
        if element is not None:
            text = (element.get("message") or element.text or "").strip()
            return " | ".join(line.strip() for line in text.splitlines()[:3] if line.strip())[:400]
    return ""


def detail_failed(path):
    try:
        return any(classify(c) == "failed" for c in ET.parse(path).getroot().iter("testcase"))
    except ET.ParseError:
        return True


def main(folder):
    counts = {"passed": 0, "failed": 0, "skipped": 0}
    failures = []
    for root, _, files in os.walk(folder):
        for name in sorted(files):
            if not name.endswith(".xml"):
                continue
            path = os.path.join(root, name)
            try:
                tree = ET.parse(path)
            except ET.ParseError as error:
                counts["failed"] += 1
                failures.append(f"{path}: unreadable result file ({error})")
                continue
            for case in tree.getroot().iter("testcase"):
                kind = classify(case)
                # rostest writes one wrapper case "test<name>" per test node plus the node's own
                # results in rosunit-<name>.xml: count the wrapper only when those are missing,
                # or when it failed although they did not (e.g. the node timed out).
                if name.startswith("rostest-") and (case.get("name") or "").startswith("test"):
                    detail = os.path.join(root, "rosunit-" + case.get("name")[len("test"):] + ".xml")
                    if os.path.isfile(detail) and (kind != "failed" or detail_failed(detail)):
                        continue
                counts[kind] += 1
                if kind == "failed":
                    reason = failure_reason(case)
                    failures.append(f"{os.path.relpath(path, folder)}: {case.get('classname')}.{case.get('name')}"
                                    + (f": {reason}" if reason else ""))
    for line in failures:
        print(f"FAILED {line}")
    total = sum(counts.values())
    if total == 0:
        print("no test results found")
    print(f"{counts['passed']} passed, {counts['failed']} failed, {counts['skipped']} skipped")
    return 1 if counts["failed"] or total == 0 else 0


if __name__ == "__main__":
    sys.exit(main(sys.argv[1] if len(sys.argv) > 1 else "."))
