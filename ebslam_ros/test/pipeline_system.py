#!/usr/bin/python3
"""System test of the whole pipeline: the recorded session (test/data/session/session.bag) played by
launch/playback.launch through DASP, s-DASP and EB-SLAM-2D. Asserts that superpixels, segments and
poses arrive at their expected rates, in their frames, with sane content: superpixel and segment
counts in a range, the pose trajectory within a bound of the simulator's ground truth."""
import sys
import threading
import time
import unittest

import numpy as np
import rospy
import rostest
from ebslam_msgs.msg import Segmentation, SuperpixelArray
from geometry_msgs.msg import PoseStamped, PoseWithCovarianceStamped


def aligned_rmse(estimated, reference):
    mu_e, mu_r = estimated.mean(axis=0), reference.mean(axis=0)
    u, _, vt = np.linalg.svd((reference - mu_r).T @ (estimated - mu_e))
    d = np.diag([1.0, np.sign(np.linalg.det(u @ vt))])
    rotation = u @ d @ vt
    aligned = (rotation @ (estimated - mu_e).T).T + mu_r
    return float(np.sqrt(np.mean(np.sum((aligned - reference) ** 2, axis=1))))


class PipelineSystemTest(unittest.TestCase):
    def setUp(self):
        self.lock = threading.Lock()
        self.superpixels, self.segmentations, self.poses, self.truth = [], [], [], []
        rospy.Subscriber("/camera/superpixels", SuperpixelArray, self.store(self.superpixels), queue_size=50)
        rospy.Subscriber("/camera/segmentation", Segmentation, self.store(self.segmentations), queue_size=50)
        rospy.Subscriber("/ebslam/pose", PoseWithCovarianceStamped, self.store(self.poses), queue_size=5000)
        rospy.Subscriber("/ground_truth/pose", PoseStamped, self.store_truth, queue_size=5000)
        self.last_truth_wall = time.monotonic()

    def store_truth(self, msg):
        with self.lock:
            self.truth.append(msg)
            self.last_truth_wall = time.monotonic()

    def store(self, target):
        def callback(msg):
            with self.lock:
                target.append(msg)
        return callback

    def test_outputs_of_the_session(self):
        # The session is 8 s of bag time: 24-25 RGB-D frames at 3 Hz, events at 100 messages/s.
        # Wall time: the nodes run on the bag's /clock, which stops when the bag ends.
        deadline = time.monotonic() + rospy.get_param("~timeout", 240.0)
        while not rospy.is_shutdown() and len(self.segmentations) < 24 and time.monotonic() < deadline:
            time.sleep(0.5)
        # Then the poses catch up with the end of the bag: the ground truth has stopped (the bag
        # ended) and the newest pose is as late as the newest ground truth, within a message.
        def caught_up():
            with self.lock:
                if not self.poses or not self.truth:
                    return False
                quiet = time.monotonic() - self.last_truth_wall > 1.0
                return quiet and (self.poses[-1].header.stamp.to_sec()
                                  >= self.truth[-1].header.stamp.to_sec() - 0.05)
        while not rospy.is_shutdown() and not caught_up() and time.monotonic() < deadline:
            time.sleep(0.1)
        with self.lock:
            superpixels, segmentations = list(self.superpixels), list(self.segmentations)
            poses, truth = list(self.poses), list(self.truth)
        self.assertGreaterEqual(len(superpixels), 20, "superpixels: %d messages" % len(superpixels))
        self.assertGreaterEqual(len(segmentations), 20, "segmentation: %d messages" % len(segmentations))
        for msg in superpixels:
            self.assertEqual(msg.header.frame_id, "camera_rgb_optical_frame")
            self.assertTrue(500 <= len(msg.superpixels) <= 1100, len(msg.superpixels))
            self.assertGreater(len(msg.edges), len(msg.superpixels))
        stamps = [m.header.stamp.to_sec() for m in superpixels]
        span = stamps[-1] - stamps[0]
        self.assertAlmostEqual((len(stamps) - 1) / span, 3.0, delta=0.5)  # the bag's RGB-D rate
        for msg in segmentations:
            segments = len(set(msg.segment_ids))
            self.assertTrue(2 <= segments <= 150, "%d segments" % segments)
        self.assertGreaterEqual(len(poses), 500, "pose: %d messages" % len(poses))
        self.assertTrue(all(p.header.frame_id == "map" for p in poses))
        # Position RMSE against the ground truth at the same time, after a rigid 2D alignment
        # (Umeyama, no scale), as the trajectory evaluation of thesis 6.5 / 7.3 does.
        truth_t = np.array([t.header.stamp.to_sec() for t in truth])
        estimated, reference = [], []
        for p in poses:
            i = int(np.argmin(np.abs(truth_t - p.header.stamp.to_sec())))
            if abs(truth_t[i] - p.header.stamp.to_sec()) > 0.03:
                continue
            estimated.append([p.pose.pose.position.x, p.pose.pose.position.y])
            reference.append([truth[i].pose.position.x, truth[i].pose.position.y])
        self.assertGreater(len(estimated), 300)
        rmse = aligned_rmse(np.array(estimated), np.array(reference))
        rospy.loginfo("pipeline system test: %d superpixel arrays, %d segmentations, %d poses, "
                      "position RMSE %.3f m", len(superpixels), len(segmentations), len(poses), rmse)
        self.assertLess(rmse, 0.06)  # 3.2 cm measured


if __name__ == "__main__":
    rospy.init_node("pipeline_system_test")
    rostest.rosrun("ebslam_ros", "pipeline_system", PipelineSystemTest, sys.argv)
