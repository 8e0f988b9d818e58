#!/usr/bin/python3
"""launch/simulation.launch draws the estimate and the ground truth where they belong: EB-SLAM-2D's
base_link poses (frame map) mapped through the simulator's static world -> map lie over the ground
truth (frame world) at the same stamps, in position and heading, with no fitted alignment."""
import math
import sys
import threading
import time
import unittest

import numpy as np
import rospy
import rostest
import tf2_ros
from geometry_msgs.msg import PoseStamped, PoseWithCovarianceStamped


def yaw_of(q):
    return math.atan2(2.0 * (q.w * q.z + q.x * q.y), 1.0 - 2.0 * (q.y * q.y + q.z * q.z))


def wrap(angle):
    return (angle + math.pi) % (2.0 * math.pi) - math.pi


class SimulationOverlayTest(unittest.TestCase):
    def setUp(self):
        self.lock = threading.Lock()
        self.estimates, self.truth = [], []
        self.tf_buffer = tf2_ros.Buffer()
        self.tf_listener = tf2_ros.TransformListener(self.tf_buffer)
        rospy.Subscriber("/ebslam/pose", PoseWithCovarianceStamped, self.store_estimate, queue_size=5000)
        rospy.Subscriber("/ground_truth/pose", PoseStamped, self.store_truth, queue_size=5000)

    def store_estimate(self, msg):
        with self.lock:
            self.estimates.append((msg.header.frame_id, msg.header.stamp.to_sec(), msg.pose.pose))

    def store_truth(self, msg):
        with self.lock:
            self.truth.append((msg.header.frame_id, msg.header.stamp.to_sec(), msg.pose))

    def test_estimate_lies_over_the_ground_truth(self):
        # The scenario is 12 s of simulated time; the ground truth stops at its end.
        deadline = time.monotonic() + 90.0
        while not rospy.is_shutdown() and time.monotonic() < deadline:
            with self.lock:
                span = self.truth[-1][1] - self.truth[0][1] if self.truth else 0.0
                done = span > 10.0 and self.estimates and self.estimates[-1][1] >= self.truth[-1][1] - 0.05
            if done:
                break
            time.sleep(0.2)
        with self.lock:
            estimates, truth = list(self.estimates), list(self.truth)
        self.assertGreater(len(truth), 500, "ground truth poses received")
        self.assertGreater(len(estimates), 500, "EB-SLAM-2D poses received")
        self.assertEqual({e[0] for e in estimates}, {"map"})
        self.assertEqual({t[0] for t in truth}, {"world"})
        world_map = self.tf_buffer.lookup_transform("world", "map", rospy.Time(0), rospy.Duration(5.0))
        tx, ty = world_map.transform.translation.x, world_map.transform.translation.y
        map_yaw = yaw_of(world_map.transform.rotation)
        c, s = math.cos(map_yaw), math.sin(map_yaw)
        t_truth = np.array([t[1] for t in truth])
        x_truth = np.array([t[2].position.x for t in truth])
        y_truth = np.array([t[2].position.y for t in truth])
        yaw_truth = np.unwrap([yaw_of(t[2].orientation) for t in truth])
        distances, headings = [], []
        for _, stamp, pose in estimates:
            if stamp < t_truth[0] or stamp > t_truth[-1]:
                continue
            x = tx + c * pose.position.x - s * pose.position.y
            y = ty + s * pose.position.x + c * pose.position.y
            distances.append(math.hypot(x - np.interp(stamp, t_truth, x_truth),
                                        y - np.interp(stamp, t_truth, y_truth)))
            headings.append(abs(wrap(map_yaw + yaw_of(pose.orientation) -
                                     np.interp(stamp, t_truth, yaw_truth))))
        self.assertGreater(len(distances), 500)
        median_m, worst_m = float(np.median(distances)), float(np.max(distances))
        median_deg = math.degrees(float(np.median(headings)))
        rospy.loginfo("estimate vs ground truth in world: median %.3f m, max %.3f m, heading median %.1f deg",
                      median_m, worst_m, median_deg)
        # Measured 0.09-0.10 m median, 0.17 m max, 3 deg (speeds 1 and 2, loop on and off).
        self.assertLess(median_m, 0.25)
        self.assertLess(worst_m, 0.5)
        self.assertLess(median_deg, 10.0)


if __name__ == "__main__":
    rospy.init_node("simulation_overlay_test")
    rostest.rosrun("ebslam_ros", "simulation_overlay", SimulationOverlayTest, sys.argv)
