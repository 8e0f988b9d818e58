#!/usr/bin/python3
"""System test of live.launch slam:=ebslam3d without hardware: the eDVS emulator (edvs_driver's
edvs_emulator, its event generator on a pseudo-terminal) stands in for the eDVS and
dasp_ros/RgbdFolderSource on the sample session (rgbd_folder:=, with a calibration of that folder's
VGA depth camera) for the RGB-D camera. The emulator starts first, so the driver opens its link at
the first try; then live.launch runs against this rostest's master (a subprocess). Asserts that
every node of the launch is up and answers, the 3D pipeline's topics carry messages (events, depth
frames, fused depth events, EB-SLAM-3D poses and map, the rig's tf), and that no node logged an
ERROR or FATAL (/rosout_agg and the launch's own output)."""
import os
import shutil
import subprocess
import sys
import tempfile
import threading
import time
import unittest

import rosgraph
import rosnode
import rospkg
import rospy
import rostest
from ebslam_msgs.msg import DepthEventArray, EventArray
from geometry_msgs.msg import PoseWithCovarianceStamped
from rosgraph_msgs.msg import Log
from sensor_msgs.msg import CameraInfo, PointCloud2
from tf2_msgs.msg import TFMessage

# Starting, stopping and reading launch output: ebslam_msgs/test/launch_output.py (shared with the
# startup-policy rostest).
sys.path.insert(0, os.path.join(rospkg.RosPack().get_path("ebslam_msgs"), "test"))
import launch_output  # noqa: E402

NODES = ["/camera/camera_manager", "/camera/rgbd_folder_source", "/camera/dasp", "/camera/sdasp",
         "/edvs/edvs_manager", "/edvs/edvs_driver", "/edvs/event_renderer", "/edvs/event_denoiser",
         "/dedvs/depth_event_fusion", "/ebslam3d/event_slam3d"]
# The depth images' camera_info, not the images: deserialising 30 VGA frames/s in Python would load
# the shared cores more than the pipeline does.
TOPICS = {"/edvs/events": EventArray, "/camera/depth_registered/camera_info": CameraInfo,
          "/dedvs/depth_events": DepthEventArray, "/ebslam3d/pose": PoseWithCovarianceStamped,
          "/ebslam3d/map": PointCloud2}
RUN_S = 20.0  # seconds of running after every topic has carried a message


class LiveEbslam3dSystemTest(unittest.TestCase):
    def setUp(self):
        self.lock = threading.Lock()
        self.errors, self.counts, self.parents = [], {t: 0 for t in TOPICS}, {}
        self.tmp = tempfile.mkdtemp(prefix="live_ebslam3d_")
        self.link = os.path.join(self.tmp, "edvs")
        self.emulator = subprocess.Popen(
            ["rosrun", "edvs_driver", "edvs_emulator", "--link", self.link, "--rate", "20000",
             "--baud", "4000000"], stdout=subprocess.DEVNULL, stderr=subprocess.DEVNULL,
            start_new_session=True)
        self.launch = None
        self.launch_log = os.path.join(self.tmp, "roslaunch.log")

    def tearDown(self):
        for process in (self.launch, self.emulator):
            launch_output.stop(process, grace_s=30)
        shutil.rmtree(self.tmp, ignore_errors=True)

    def on_log(self, msg):
        if msg.level >= Log.ERROR:
            with self.lock:
                self.errors.append(f"{msg.name}: {msg.msg}")

    def counter(self, topic):
        def callback(_msg):
            with self.lock:
                self.counts[topic] += 1
        return callback

    def on_tf(self, msg):
        with self.lock:
            for t in msg.transforms:
                self.parents[t.child_frame_id] = t.header.frame_id

    def test_every_node_starts_without_error(self):
        deadline = time.monotonic() + 30
        while not os.path.exists(self.link) and time.monotonic() < deadline:
            time.sleep(0.1)
        self.assertTrue(os.path.exists(self.link), "the emulator made no link")
        rospy.Subscriber("/rosout_agg", Log, self.on_log, queue_size=1000)
        for topic, kind in TOPICS.items():
            rospy.Subscriber(topic, kind, self.counter(topic), queue_size=100)
        rospy.Subscriber("/tf", TFMessage, self.on_tf, queue_size=100)
        rospy.Subscriber("/tf_static", TFMessage, self.on_tf, queue_size=100)
        calibration = rospy.get_param("~calibration")
        folder = rospy.get_param("~rgbd_folder")
        with open(self.launch_log, "w") as log:
            self.launch = launch_output.start(
                ["roslaunch", "ebslam_ros", "live.launch", "slam:=ebslam3d",
                 f"uri:=serial://{self.link}?format=E2", f"rgbd_folder:={folder}",
                 f"dedvs_calibration:={calibration}"], log)
        deadline = time.monotonic() + rospy.get_param("~startup_timeout", 120.0)

        def all_flowing():
            with self.lock:
                return all(c > 0 for c in self.counts.values())
        while not all_flowing() and time.monotonic() < deadline and self.launch.poll() is None:
            time.sleep(0.5)
        with self.lock:
            counts = dict(self.counts)
        self.assertTrue(all_flowing(), f"topics without messages: {counts}\n{self.tail()}")
        time.sleep(RUN_S)
        self.assertIsNone(self.launch.poll(), f"roslaunch ended\n{self.tail()}")

        master = rosgraph.Master("/live_ebslam3d_system")
        down = [n for n in NODES if not rosnode.rosnode_ping(n, max_count=1)]
        self.assertEqual(down, [], f"nodes not answering: {down}")
        with self.lock:
            parents, errors, counts = dict(self.parents), list(self.errors), dict(self.counts)
        self.assertEqual(parents.get("odom"), "map")
        self.assertEqual(parents.get("base_link"), "odom")
        self.assertEqual(parents.get("edvs_optical_frame"), "base_link")
        self.assertEqual(parents.get("camera_rgb_optical_frame"), "edvs_optical_frame")
        launch_errors = launch_output.problem_lines(launch_output.read(self.launch_log))
        rospy.loginfo("live_ebslam3d_system: %s; %d nodes of %d answer (master %s)", counts,
                      len(NODES) - len(down), len(NODES), master.getUri())
        self.assertEqual(errors, [], "ERROR/FATAL on /rosout_agg")
        self.assertEqual(launch_errors, [], "ERROR in the launch output")

    def tail(self):
        return launch_output.read(self.launch_log)[-3000:]


if __name__ == "__main__":
    rospy.init_node("live_ebslam3d_system")
    rostest.rosrun("ebslam_ros", "live_ebslam3d_system", LiveEbslam3dSystemTest, sys.argv)
