#!/usr/bin/python3
"""rostest of the workspace's startup-failure policy (ebslam_ros_common/ros_param_helpers.h) for one
nodelet, driven by the .test file's private parameters:

  ~node_pkg, ~node_type  the standalone node that runs the nodelet (e.g. ebslam_ros
                         event_particle_filter_node)
  ~nodelet               the nodelet type (e.g. ebslam_ros/EventParticleFilter)
  ~good_args             private parameters with which it starts (space-separated _name:=value)
  ~bad_param, ~bad_value a parameter whose value cannot work
  ~wrong_type_param, ~wrong_type_value  (optional) a parameter set with the wrong type
  ~unknown_param, ~expected_suggestion  a misspelled parameter and the name the WARN suggests

Asserts: the node with the bad value logs FATAL naming the parameter's full name and exits
non-zero; so does the wrong type; in a launch file with a manager and `nodelet load` marked
required="true", the bad value ends roslaunch; with the unknown parameter the node runs and logs
a WARN naming it and suggesting the known one.
"""
import os
import signal
import subprocess
import sys
import tempfile
import time
import unittest

import rospy
import rostest

EXIT_TIMEOUT_S = 40.0


def private(name, default=None):
    return str(rospy.get_param("~" + name, default) if default is not None else rospy.get_param("~" + name))


def run_until_exit(command, timeout_s=EXIT_TIMEOUT_S):
    """(returncode or None if still running at the timeout, combined output)."""
    with tempfile.TemporaryFile() as log:
        process = subprocess.Popen(command, stdout=log, stderr=subprocess.STDOUT,
                                   stdin=subprocess.DEVNULL, start_new_session=True)
        try:
            code = process.wait(timeout=timeout_s)
        except subprocess.TimeoutExpired:
            os.killpg(process.pid, signal.SIGINT)
            try:
                process.wait(timeout=10)
            except subprocess.TimeoutExpired:
                os.killpg(process.pid, signal.SIGKILL)
                process.wait()
            code = None
        log.seek(0)
        return code, log.read().decode(errors="replace")


def run_until_output(command, needle, timeout_s=EXIT_TIMEOUT_S):
    """(found, still running when found, output): reads the output until `needle` appears."""
    with tempfile.NamedTemporaryFile() as log:
        process = subprocess.Popen(command, stdout=log, stderr=subprocess.STDOUT,
                                   stdin=subprocess.DEVNULL, start_new_session=True)
        deadline = time.monotonic() + timeout_s
        found = False
        output = ""
        while time.monotonic() < deadline:
            with open(log.name, errors="replace") as f:
                output = f.read()
            if needle in output:
                found = True
                break
            if process.poll() is not None:
                break
            time.sleep(0.2)
        running = process.poll() is None
        if running:
            os.killpg(process.pid, signal.SIGINT)
            try:
                process.wait(timeout=10)
            except subprocess.TimeoutExpired:
                os.killpg(process.pid, signal.SIGKILL)
                process.wait()
        with open(log.name, errors="replace") as f:
            output = f.read()
        return found, running, output


class StartupPolicyTest(unittest.TestCase):
    @classmethod
    def setUpClass(cls):
        rospy.init_node("startup_policy_test", anonymous=True)
        cls.pkg = private("node_pkg")
        cls.node_type = private("node_type")
        cls.nodelet = private("nodelet")
        cls.good_args = private("good_args", "").split()

    def node_command(self, name, extra):
        return ["rosrun", self.pkg, self.node_type, f"__name:={name}"] + self.good_args + extra

    def assert_fatal_exit(self, name, param, value):
        code, output = run_until_exit(self.node_command(name, [f"_{param}:={value}"]))
        self.assertIsNotNone(code, f"node still running {EXIT_TIMEOUT_S} s after a bad ~{param}:\n"
                             + output[-3000:])
        self.assertNotEqual(code, 0, output[-3000:])
        fatal = [line for line in output.splitlines() if "FATAL" in line]
        self.assertTrue(fatal, "no FATAL line:\n" + output[-3000:])
        self.assertTrue(any(f"/{name}/{param}" in line for line in fatal),
                        f"FATAL does not name /{name}/{param}:\n" + "\n".join(fatal))

    def test_bad_value_is_fatal_and_exits(self):
        self.assert_fatal_exit("policy_bad_value", private("bad_param"), private("bad_value"))

    def test_wrong_type_is_fatal_and_exits(self):
        if not rospy.has_param("~wrong_type_param"):
            self.skipTest("no ~wrong_type_param given")
        self.assert_fatal_exit("policy_wrong_type", private("wrong_type_param"),
                               private("wrong_type_value"))

    def test_required_nodelet_ends_the_launch(self):
        # A manager and `nodelet load ... required="true"`: the failed load must end roslaunch.
        params = "\n".join(
            f'    <param name="{arg.split(":=", 1)[0].lstrip("_")}" value="{arg.split(":=", 1)[1]}"/>'
            for arg in self.good_args + [f"_{private('bad_param')}:={private('bad_value')}"])
        launch = f"""<launch>
  <node pkg="nodelet" type="nodelet" name="policy_manager" args="manager"/>
  <node pkg="nodelet" type="nodelet" name="policy_required" required="true"
        args="load {self.nodelet} policy_manager">
{params}
  </node>
</launch>
"""
        with tempfile.NamedTemporaryFile("w", suffix=".launch") as f:
            f.write(launch)
            f.flush()
            start = time.monotonic()
            code, output = run_until_exit(["roslaunch", f.name])
        self.assertIsNotNone(code, "roslaunch still running with a failed required nodelet:\n"
                             + output[-3000:])
        self.assertIn("policy_required", output)
        self.assertLess(time.monotonic() - start, EXIT_TIMEOUT_S)

    def test_unknown_parameter_warns_with_suggestion(self):
        name = "policy_unknown"
        unknown = private("unknown_param")
        suggestion = f"/{name}/{private('expected_suggestion')}"
        needle = f"parameter /{name}/{unknown} is not a parameter of this node"
        found, running, output = run_until_output(self.node_command(name, [f"_{unknown}:=1"]),
                                                  needle)
        self.assertTrue(found, "no WARN about the unknown parameter:\n" + output[-3000:])
        self.assertTrue(running, "the node stopped on an unknown parameter:\n" + output[-3000:])
        line = next(l for l in output.splitlines() if needle in l)
        self.assertIn("WARN", line)
        self.assertIn(f"did you mean {suggestion}?", line)


if __name__ == "__main__":
    rostest.rosrun("ebslam_ros_common", "startup_policy", StartupPolicyTest, sys.argv)
