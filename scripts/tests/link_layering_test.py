#!/usr/bin/python3
"""What the built workspace links, against the layering of src/ebslam (docs/ebslam_core.md):

  - the eDVS core (edvs::edvs), ebslam_msgs, edvs_driver and dasp_ros link at most the events
    library of src/ebslam: never ebslam::slam, ebslam::simulation, ebslam::calibration, the
    ebslam::ebslam umbrella, nor Ceres (read from the exported CMake targets and the link lines);
  - their shared objects define no symbol of a type declared in src/ebslam's slam/, simulation/ or
    calibration/ headers, and none of Ceres (`nm -C --defined-only`);
  - only ebslam::calibration links Ceres among the ebslam targets.

Usage: link_layering_test.py WS_DIR [JUNIT_XML]   (exit 1 on a failure)
"""
import glob
import os
import re
import subprocess
import sys
import unittest

REPO = os.path.dirname(os.path.dirname(os.path.dirname(os.path.abspath(__file__))))
WS = None
# Libraries the lower layers must not link (file names on the link lines).
FORBIDDEN_LIBS = re.compile(
    r"libebslam\.a|libebslam_(slam|simulation|calibration)\.a|libceres|libglog")
FORBIDDEN_TARGETS = re.compile(r"ebslam::(ebslam|slam|simulation|calibration)\b|Ceres::")
# Packages whose build must stay below the SLAM, simulation and calibration code.
LOWER_PACKAGES = ("edvs", "ebslam_msgs", "edvs_driver", "dasp_ros")


def upper_layer_types():
    """Class and struct names declared in src/ebslam's slam/, simulation/, calibration/ headers."""
    names = set()
    for part in ("slam", "simulation", "calibration"):
        for header in glob.glob(os.path.join(REPO, "src/ebslam/include/ebslam", part, "*.h")):
            with open(header) as f:
                names.update(re.findall(r"^(?:class|struct) (\w+)\b[^;]*$", f.read(), re.M))
    return names


def exported_links(targets_file):
    """target name -> INTERFACE_LINK_LIBRARIES of an exported <pkg>Targets.cmake."""
    with open(targets_file) as f:
        text = f.read()
    links = {}
    for target, body in re.findall(r"set_target_properties\((\S+) PROPERTIES(.*?)\n\)", text, re.S):
        m = re.search(r'INTERFACE_LINK_LIBRARIES "([^"]*)"', body)
        links[target] = m.group(1) if m else ""
    return links


class LinkLayeringTest(unittest.TestCase):
    def test_exported_targets(self):
        edvs = exported_links(os.path.join(WS, "devel/lib/cmake/edvs/edvsTargets.cmake"))
        self.assertIn("edvs::edvs", edvs)
        self.assertIn("ebslam::events", edvs["edvs::edvs"])
        self.assertIsNone(FORBIDDEN_TARGETS.search(edvs["edvs::edvs"]), edvs["edvs::edvs"])
        ebslam = exported_links(os.path.join(WS, "devel/lib/cmake/ebslam/ebslamTargets.cmake"))
        for target in ("ebslam::events", "ebslam::slam", "ebslam::simulation",
                       "ebslam::calibration"):
            self.assertIn(target, ebslam)
        self.assertNotRegex(ebslam["ebslam::events"], r"ebslam::|Ceres|opencv")
        for target, links in ebslam.items():
            if target not in ("ebslam::calibration", "ebslam::ebslam"):
                self.assertNotIn("Ceres", links, target)

    def test_link_lines(self):
        checked = 0
        for package in LOWER_PACKAGES:
            for link in glob.glob(os.path.join(WS, "build", package, "CMakeFiles", "*", "link.txt")):
                with open(link) as f:
                    line = f.read()
                self.assertIsNone(FORBIDDEN_LIBS.search(line), f"{link}: {line[:400]}")
                checked += 1
        self.assertGreater(checked, 10, "no link lines found: is the workspace built?")

    def test_defined_symbols(self):
        types = upper_layer_types()
        self.assertGreater(len(types), 20, "the slam/simulation/calibration headers declare types")
        pattern = re.compile(r"\bebslam::(%s)\b|\bceres::" % "|".join(sorted(types)))
        objects = []
        for package in LOWER_PACKAGES[1:]:
            objects += glob.glob(os.path.join(WS, "devel/.private", package, "lib", "*.so"))
        self.assertGreaterEqual(len(objects), 3, objects)
        for obj in objects:
            out = subprocess.run(["nm", "-C", "--defined-only", obj], capture_output=True,
                                 text=True, check=True).stdout
            found = sorted({m.group(0) for m in pattern.finditer(out)})
            self.assertEqual(found, [], obj)


if __name__ == "__main__":
    WS = os.path.abspath(sys.argv[1])
    junit = sys.argv[2] if len(sys.argv) > 2 else None
    suite = unittest.defaultTestLoader.loadTestsFromTestCase(LinkLayeringTest)
    tests = list(suite)
    result = unittest.TextTestRunner(verbosity=2).run(suite)
    if junit:
        sys.path.insert(0, os.path.dirname(os.path.abspath(__file__)))
        from workspace_checks import write_junit  # noqa: E402
        write_junit(result, tests, junit, "link_layering")
    sys.exit(0 if result.wasSuccessful() else 1)
