#!/usr/bin/python3
"""rostest of the workspace's startup-failure policy (ebslam_msgs/ros_param_helpers.h) for every
nodelet of one package, under one master. Private parameters of the .test file:

  ~package               the package; every class of its nodelet_plugins.xml needs a namespace below
  ~jobs                  how many nodelets are checked side by side (default 3)
  ~<key>/...             one namespace per nodelet (e.g. ~event_slam2d/node_type):
    node_pkg, node_type  the standalone node that runs the nodelet (e.g. ebslam_ros
                         event_particle_filter_node)
    nodelet              the nodelet type (e.g. ebslam_ros/EventParticleFilter)
    good_args            private parameters with which it starts (space-separated _name:=value)
    bad_param, bad_value a parameter whose value cannot work
    wrong_type_param, wrong_type_value  a parameter set with the wrong type
    unknown_param, expected_suggestion  a misspelled parameter and the name the WARN suggests

Asserts per nodelet, each a test case of its own (test_<key>_...): the node with the bad value logs
FATAL naming the parameter's full name and exits non-zero; so does the wrong type; in a launch file
with a manager and `nodelet load` marked required="true", the bad value ends roslaunch; with the
unknown parameter the node runs and logs a WARN naming it and suggesting the known one. The cases
of all nodelets start at once on a pool of ~jobs threads (each case is a subprocess that mostly
waits for a node to start), and each test method waits for its own case's outcome.
"""
import concurrent.futures
import os
import sys
import tempfile
import time
import unittest
import xml.etree.ElementTree as ET

import rospkg
import rospy
import rostest

# launch_output.py lies beside this file (also where catkin's relay script runs it from elsewhere).
sys.path.insert(0, os.path.dirname(os.path.abspath(__file__)))
from launch_output import problem_lines, run_until_exit, run_until_output  # noqa: E402

EXIT_TIMEOUT_S = 40.0
CASE_FIELDS = ("node_pkg", "node_type", "nodelet", "bad_param", "bad_value", "wrong_type_param",
               "wrong_type_value", "unknown_param", "expected_suggestion")


class Nodelet:
    """One nodelet's parameters (a namespace of the test) and the runs of its four cases."""

    def __init__(self, key, params):
        self.key = key
        self.p = {name: str(value) for name, value in params.items()}
        self.good_args = self.p.get("good_args", "").split()
        # Node names unique per nodelet: the cases of every nodelet share one master.
        self.prefix = f"policy_{key}"

    def node_command(self, name, extra):
        return ["rosrun", self.p["node_pkg"], self.p["node_type"], f"__name:={name}"] + \
            self.good_args + extra

    def fatal_exit(self, case, param, value):
        name = f"{self.prefix}_{case}"
        code, output = run_until_exit(self.node_command(name, [f"_{param}:={value}"]),
                                      EXIT_TIMEOUT_S)
        return {"name": name, "param": param, "code": code, "output": output}

    def bad_value(self):
        return self.fatal_exit("bad_value", self.p["bad_param"], self.p["bad_value"])

    def wrong_type(self):
        return self.fatal_exit("wrong_type", self.p["wrong_type_param"],
                               self.p["wrong_type_value"])

    def required_launch(self):
        # A manager and `nodelet load ... required="true"`: the failed load must end roslaunch.
        args = self.good_args + [f"_{self.p['bad_param']}:={self.p['bad_value']}"]
        params = "\n".join(
            f'    <param name="{arg.split(":=", 1)[0].lstrip("_")}" value="{arg.split(":=", 1)[1]}"/>'
            for arg in args)
        launch = f"""<launch>
  <node pkg="nodelet" type="nodelet" name="{self.prefix}_manager" args="manager"/>
  <node pkg="nodelet" type="nodelet" name="{self.prefix}_required" required="true"
        args="load {self.p['nodelet']} {self.prefix}_manager">
{params}
  </node>
</launch>
"""
        with tempfile.NamedTemporaryFile("w", suffix=".launch") as f:
            f.write(launch)
            f.flush()
            start = time.monotonic()
            code, output = run_until_exit(["roslaunch", f.name], EXIT_TIMEOUT_S)
        return {"code": code, "output": output, "seconds": time.monotonic() - start}

    def unknown(self):
        name = f"{self.prefix}_unknown"
        needle = f"parameter /{name}/{self.p['unknown_param']} is not a parameter of this node"
        found, running, output = run_until_output(
            self.node_command(name, [f"_{self.p['unknown_param']}:=1"]), needle, EXIT_TIMEOUT_S)
        return {"name": name, "needle": needle, "found": found, "running": running,
                "output": output}


class StartupPolicyTest(unittest.TestCase):
    futures = {}
    pool = None

    @classmethod
    def setUpClass(cls):
        cls.pool = concurrent.futures.ThreadPoolExecutor(max_workers=JOBS)
        for key, nodelet in NODELETS.items():
            for case in ("bad_value", "wrong_type", "required_launch", "unknown"):
                cls.futures[(key, case)] = cls.pool.submit(getattr(nodelet, case))

    @classmethod
    def tearDownClass(cls):
        cls.pool.shutdown(wait=True)

    def outcome(self, key, case):
        return self.futures[(key, case)].result()

    def assert_fatal_exit(self, r):
        self.assertIsNotNone(r["code"], f"node still running {EXIT_TIMEOUT_S} s after a bad "
                             f"~{r['param']}:\n" + r["output"][-3000:])
        self.assertNotEqual(r["code"], 0, r["output"][-3000:])
        fatal = problem_lines(r["output"], levels=("FATAL",), died=False)
        self.assertTrue(fatal, "no FATAL line:\n" + r["output"][-3000:])
        self.assertTrue(any(f"/{r['name']}/{r['param']}" in line for line in fatal),
                        f"FATAL does not name /{r['name']}/{r['param']}:\n" + "\n".join(fatal))

    def check_bad_value(self, key):
        self.assert_fatal_exit(self.outcome(key, "bad_value"))

    def check_wrong_type(self, key):
        self.assert_fatal_exit(self.outcome(key, "wrong_type"))

    def check_required_launch(self, key):
        r = self.outcome(key, "required_launch")
        self.assertIsNotNone(r["code"], "roslaunch still running with a failed required nodelet:\n"
                             + r["output"][-3000:])
        self.assertIn(f"{NODELETS[key].prefix}_required", r["output"])
        self.assertLess(r["seconds"], EXIT_TIMEOUT_S)

    def check_unknown(self, key):
        r = self.outcome(key, "unknown")
        nodelet = NODELETS[key]
        self.assertTrue(r["found"], "no WARN about the unknown parameter:\n" + r["output"][-3000:])
        self.assertTrue(r["running"], "the node stopped on an unknown parameter:\n"
                        + r["output"][-3000:])
        line = next(l for l in r["output"].splitlines() if r["needle"] in l)
        self.assertIn("WARN", line)
        self.assertIn(f"did you mean /{r['name']}/{nodelet.p['expected_suggestion']}?", line)

    def test_every_nodelet_has_cases(self):
        path = rospkg.RosPack().get_path(PACKAGE) + "/nodelet_plugins.xml"
        classes = {c.get("name") for c in ET.parse(path).getroot().iter("class")}
        covered = {n.p["nodelet"] for n in NODELETS.values()}
        self.assertEqual(sorted(classes - covered), [], f"nodelets of {path} without cases")


def add_cases(cls):
    """test_<key>_<case> for every nodelet: each case passes or fails on its own in the count."""
    names = {"bad_value": "bad_value_is_fatal_and_exits",
             "wrong_type": "wrong_type_is_fatal_and_exits",
             "required_launch": "required_nodelet_ends_the_launch",
             "unknown": "unknown_parameter_warns_with_suggestion"}
    for key in NODELETS:
        for case, title in names.items():
            check = getattr(cls, f"check_{case}")
            setattr(cls, f"test_{key}_{title}", lambda self, k=key, c=check: c(self, k))


if __name__ == "__main__":
    rospy.init_node("startup_policy_test", anonymous=True)
    PACKAGE = str(rospy.get_param("~package"))
    JOBS = int(rospy.get_param("~jobs", 3))
    NODELETS = {}
    for key, params in sorted(rospy.get_param("~").items()):
        if isinstance(params, dict):
            missing = [f for f in CASE_FIELDS if f not in params]
            if missing:
                sys.exit(f"startup_policy: ~{key} lacks {missing}")
            NODELETS[key] = Nodelet(key, params)
    add_cases(StartupPolicyTest)
    rostest.rosrun("ebslam_msgs", f"startup_policy_{PACKAGE}", StartupPolicyTest, sys.argv)
