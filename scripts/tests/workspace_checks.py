#!/usr/bin/python3
"""Checks of the workspace as a whole (no build needed), run by `scripts/ws.sh test`.

  - scripts/check_package_deps.py passes on the tree, and fails, naming the package, when one
    declaration is removed from a package.xml in a copy of the tree (a CMake find, a Python import, a
    launch-file reference, a test-only find);

Usage: workspace_checks.py [JUNIT_XML]   (writes a JUnit file when given; exit 1 on a failure)
"""
import glob
import os
import re
import shutil
import subprocess
import sys
import tempfile
import unittest
import xml.etree.ElementTree as ET

REPO = os.path.dirname(os.path.dirname(os.path.dirname(os.path.abspath(__file__))))
CHECK = os.path.join(REPO, "scripts", "check_package_deps.py")


def run_check(root):
    result = subprocess.run(["/usr/bin/python3", CHECK, "--root", root], capture_output=True,
                            text=True, check=False)
    return result.returncode, result.stdout + result.stderr


class PackageDepsTest(unittest.TestCase):
    def test_tree_is_complete(self):
        status, output = run_check(REPO)
        self.assertEqual(status, 0, output)
        self.assertIn("0 gaps", output)

    def assert_removal_detected(self, package_dir, declaration, expected):
        with tempfile.TemporaryDirectory(prefix="package_deps_") as tmp:
            copy = os.path.join(tmp, "repo")
            shutil.copytree(REPO, copy, ignore=shutil.ignore_patterns(
                ".ws", ".git", "docs", "test", "demo_output", "__pycache__", "*.png", "*.bag"))
            manifest = os.path.join(copy, package_dir, "package.xml")
            with open(manifest) as f:
                text = f.read()
            self.assertEqual(text.count(declaration), 1, f"{declaration} in {manifest}")
            with open(manifest, "w") as f:
                f.write(text.replace(declaration, ""))
            status, output = run_check(copy)
            self.assertEqual(status, 1, output)
            self.assertIn(expected, output)

    def test_removed_cmake_dependency_fails(self):
        self.assert_removal_detected("edvs_driver", "<build_depend>cli11</build_depend>",
                                     "edvs_driver: cmake 'CLI11'")

    def test_removed_pkg_config_dependency_fails(self):
        self.assert_removal_detected("dasp_ros", "<depend>libopenni2-dev</depend>",
                                     "dasp_ros: pkgconfig 'libopenni2'")

    def test_removed_catkin_component_fails(self):
        self.assert_removal_detected("ebslam_ros", "<depend>tf2_ros</depend>",
                                     "ebslam_ros: catkin 'tf2_ros'")

    def test_removed_python_dependency_fails(self):
        self.assert_removal_detected("dasp_ros", "<exec_depend>python3-numpy</exec_depend>",
                                     "dasp_ros: import numpy")

    def test_removed_launch_dependency_fails(self):
        self.assert_removal_detected("ebslam_ros", "<exec_depend>rviz</exec_depend>",
                                     "ebslam_ros: launch reference rviz")

    def test_removed_component_dependency_fails(self):
        self.assert_removal_detected("src/dasp", "<build_depend>opencv-contrib</build_depend>",
                                     "dasp: component 'OpenCV:ximgproc'")


def launch_files():
    files = glob.glob(os.path.join(REPO, "*", "launch", "*.launch"))
    return sorted(files)


class LaunchDocTest(unittest.TestCase):
    def test_every_arg_has_doc(self):
        missing = []
        files = launch_files()
        self.assertGreater(len(files), 10)
        for path in files:
            for arg in ET.parse(path).getroot().iter("arg"):
                # An arg with value= is a constant of the file, not something a user sets.
                if "value" in arg.attrib:
                    continue
                if not arg.get("doc", "").strip():
                    missing.append(f"{os.path.relpath(path, REPO)}: arg {arg.get('name')}")
        self.assertEqual(missing, [], "launch args without doc=:\n" + "\n".join(missing))

    def test_launch_files_find_their_files_through_packages(self):
        # $(dirname) and relative paths break in the install space; $(find pkg) does not.
        bad = []
        for path in launch_files():
            with open(path) as f:
                for number, line in enumerate(f, 1):
                    if re.search(r"\$\(dirname\)|\.\./", line):
                        bad.append(f"{os.path.relpath(path, REPO)}:{number}: {line.strip()}")
        self.assertEqual(bad, [], "\n".join(bad))


def write_junit(result, tests, path, name="workspace_checks"):
    suite = ET.Element("testsuite", name=name, tests=str(len(tests)))
    failed = {t.id(): m for t, m in result.failures + result.errors}
    for test in tests:
        case = ET.SubElement(suite, "testcase", classname=type(test).__name__,
                             name=test.id().split(".")[-1])
        if test.id() in failed:
            ET.SubElement(case, "failure", message=failed[test.id()].splitlines()[-1][:300]).text = \
                failed[test.id()]
    ET.ElementTree(suite).write(path, encoding="utf-8", xml_declaration=True)


def main():
    loader = unittest.TestLoader()
    suite = unittest.TestSuite([loader.loadTestsFromTestCase(PackageDepsTest),
                                loader.loadTestsFromTestCase(LaunchDocTest)])
    tests = [test for group in suite for test in group]
    result = unittest.TextTestRunner(verbosity=2).run(suite)
    if len(sys.argv) > 1:
        write_junit(result, tests, sys.argv[1])
    return 0 if result.wasSuccessful() else 1


if __name__ == "__main__":
    sys.exit(main())
