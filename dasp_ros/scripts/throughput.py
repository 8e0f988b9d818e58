#!/usr/bin/python3
"""Measures a running segmentation pipeline (launch/folder_segmentation.launch): input frames (by
rgb/camera_info, which carries the colour image's stamp), output frames, output rate, frames
without output, and the nodelet manager's CPU time per frame (/proc, all its threads).

Usage: throughput.py <output_topic> <seconds> [lazy]
  lazy: also subscribe to the lazy outputs (overlay, markers, cloud, segment overlay, UCM).
Prints one line of key=value pairs.
"""
import os
import sys
import threading
import time
import xmlrpc.client

import rosgraph
import rospy
from ebslam_msgs.msg import Segmentation
from sensor_msgs.msg import CameraInfo, Image, PointCloud2
from visualization_msgs.msg import MarkerArray


def manager_pid(name="/camera/manager"):
    api = rosgraph.Master("/throughput").lookupNode(name)
    _, _, pid = xmlrpc.client.ServerProxy(api).getPid("/throughput")
    return pid


def cpu_seconds(pid):
    with open(f"/proc/{pid}/stat") as f:
        fields = f.read().rsplit(")", 1)[1].split()
    return (int(fields[11]) + int(fields[12])) / os.sysconf("SC_CLK_TCK")


def main():
    output_topic, seconds = sys.argv[1], float(sys.argv[2])
    lazy = len(sys.argv) > 3 and sys.argv[3] == "lazy"
    rospy.init_node("throughput")
    lock = threading.Lock()
    inputs, outputs = {}, {}

    def on_input(msg):
        with lock:
            inputs[msg.header.stamp.to_nsec()] = time.monotonic()

    def on_output(msg):
        with lock:
            outputs[msg.header.stamp.to_nsec()] = time.monotonic()

    rospy.Subscriber("/camera/rgb/camera_info", CameraInfo, on_input, queue_size=1000)
    rospy.Subscriber(output_topic, Segmentation, on_output, queue_size=1000)
    lazy_counts = {}
    if lazy:
        for topic, kind in [("/camera/superpixels/overlay", Image), ("/camera/superpixels/markers", MarkerArray),
                            ("/camera/superpixels/cloud", PointCloud2), ("/camera/segments/overlay", Image),
                            ("/camera/segments/ucm", Image)]:
            lazy_counts[topic] = 0

            def count(_, topic=topic):
                with lock:
                    lazy_counts[topic] += 1
            rospy.Subscriber(topic, kind, count, queue_size=10, buff_size=2 ** 24)
    pid = manager_pid()
    time.sleep(5.0)  # warm up, subscriptions settle
    start, cpu_start = time.monotonic(), cpu_seconds(pid)
    time.sleep(seconds)
    end, cpu_end = time.monotonic(), cpu_seconds(pid)
    time.sleep(1.0)  # outputs of the last inputs
    with lock:
        window_in = [s for s, t in inputs.items() if start <= t < end]
        window_out = [s for s, t in outputs.items() if start <= t < end]
        skipped = [s for s in window_in if s not in outputs]
    n_out = len(window_out)
    print(f"seconds={end - start:.1f} inputs={len(window_in)} outputs={n_out} "
          f"input_rate_hz={len(window_in) / (end - start):.2f} output_rate_hz={n_out / (end - start):.2f} "
          f"inputs_without_output={len(skipped)} manager_cpu_s={cpu_end - cpu_start:.2f} "
          f"manager_cpu_ms_per_input={1e3 * (cpu_end - cpu_start) / max(1, len(window_in)):.2f}"
          + "".join(f" {t}={c}" for t, c in lazy_counts.items()))


if __name__ == "__main__":
    main()
