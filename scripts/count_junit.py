#!/usr/bin/python3
"""Counts test cases in every JUnit XML file below a folder and prints 'N passed, N failed, N skipped'.

Each <testcase> element is counted once, whatever the nesting of <testsuites>/<testsuite> (gtest >= 1.10
writes both levels, which makes catkin_test_results double count). A file that does not parse counts as
one failure. Every skipped case is named with its reason, so that a new skip cannot hide among the
expected ones; with --expected-skips FILE (lines '<pattern> | <reason>', fnmatch patterns over
'<classname>.<name>' or '<name>') a skip no line expects counts as a failure. Exit status 1 when
anything failed or no test ran at all.

Usage: count_junit.py [--expected-skips FILE] <folder or .xml file>
"""
import argparse
import fnmatch
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


def skip_reason(case):
    """Why a case was skipped: GTEST_SKIP's message (gtest XML: the <skipped> message after the
    'file:line' line; ctest JUnit: the line after 'Skipped' in the captured output)."""
    element = case.find("skipped")
    texts = []
    if element is not None:
        texts.append(element.get("message") or "")
        texts.append(element.text or "")
    out = case.find("system-out")
    if out is not None and out.text:
        lines = out.text.splitlines()
        for i, line in enumerate(lines):
            if line.rstrip().endswith("Skipped") and i + 1 < len(lines):
                texts.insert(0, lines[i + 1])
    for text in texts:
        lines = [line.strip() for line in text.splitlines() if line.strip()]
        lines = [line for line in lines if not line.endswith("Skipped") and line != "Test skipped"
                 and "[  SKIPPED ]" not in line]
        if lines:
            return lines[-1][:300]
    return "no reason given"


def case_key(case):
    name = case.get("name") or ""
    classname = case.get("classname") or ""
    if not classname or classname == name or name.startswith(classname + "."):
        return name
    return f"{classname}.{name}"


def load_expected(path):
    expected = []
    with open(path) as f:
        for number, line in enumerate(f, 1):
            line = line.strip()
            if not line or line.startswith("#"):
                continue
            pattern, _, reason = line.partition("|")
            if not reason.strip():
                raise SystemExit(f"{path}:{number}: '<pattern> | <reason>' expected")
            expected.append((pattern.strip(), reason.strip()))
    return expected


def detail_failed(path):
    try:
        return any(classify(c) == "failed" for c in ET.parse(path).getroot().iter("testcase"))
    except ET.ParseError:
        return True


def result_files(target):
    if os.path.isfile(target):
        yield os.path.dirname(target) or ".", os.path.basename(target)
        return
    for root, _, files in os.walk(target):
        for name in sorted(files):
            if name.endswith(".xml"):
                yield root, name


def main(target, expected_skips=None):
    counts = {"passed": 0, "failed": 0, "skipped": 0}
    failures, skips, unexpected = [], [], []
    expected = load_expected(expected_skips) if expected_skips else None
    base = target if os.path.isdir(target) else os.path.dirname(target) or "."
    for root, name in result_files(target):
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
            where = os.path.relpath(path, base)
            if kind == "failed":
                reason = failure_reason(case)
                failures.append(f"{where}: {case.get('classname')}.{case.get('name')}"
                                + (f": {reason}" if reason else ""))
            elif kind == "skipped":
                key = case_key(case)
                reason = skip_reason(case)
                skips.append(f"{key} ({where}): {reason}")
                if expected is not None and not any(
                        fnmatch.fnmatchcase(key, pattern) for pattern, _ in expected):
                    unexpected.append(f"{key} ({where}): {reason}")
    for line in skips:
        print(f"SKIPPED {line}")
    for line in unexpected:
        print(f"UNEXPECTED SKIP {line} (not in {expected_skips})")
    counts["failed"] += len(unexpected)
    for line in failures:
        print(f"FAILED {line}")
    total = sum(counts.values())
    if total == 0:
        print("no test results found")
    print(f"{counts['passed']} passed, {counts['failed']} failed, {counts['skipped']} skipped")
    return 1 if counts["failed"] or total == 0 else 0


if __name__ == "__main__":
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--expected-skips", help="file of expected skips ('<pattern> | <reason>')")
    parser.add_argument("target", nargs="?", default=".", help="folder of JUnit files, or one file")
    args = parser.parse_args()
    sys.exit(main(args.target, args.expected_skips))
