#!/usr/bin/python3
"""Same results through ROS: compares the label images published by the running pipeline
(RgbdFolderSource -> Dasp -> Sdasp, launch/folder_segmentation.launch with loop:=true) with the
PNGs that dasp_segment --labels and dasp_sdasp segment --labels wrote for the same frames.

Usage: same_results.py <folder> <tool_output_dir> [timeout_s]
Tool outputs: <name>_superpixels.png and <name>_segments.png (16-bit, label + 1, 0 = none).
Frames are identified by header.stamp (never header.seq, which roscpp renumbers per publisher
across processes): the colour image with the stamp of a label image names the folder frame by its
content. Prints one line per frame and a summary; exits 1 unless every frame is identical.
"""
import os
import re
import sys
import threading

import numpy as np
import rospy
from PIL import Image as PilImage
from sensor_msgs.msg import Image


def frame_names(folder):
    names = [f[: -len("_rgb.png")] for f in os.listdir(folder) if f.endswith("_rgb.png")]
    names = [n for n in names if os.path.exists(os.path.join(folder, n + "_depth_mm.png"))]

    def key(name):
        digits = re.findall(r"\d+", name)
        return (re.sub(r"\d+", "", name), int(digits[-1]) if digits else -1, name)

    return sorted(names, key=key)


def labels_of(msg):
    assert msg.encoding == "32SC1", msg.encoding
    return np.frombuffer(msg.data, dtype="<i4").reshape(msg.height, msg.step // 4)[:, : msg.width]


def colour_of(msg):
    """The colour image message as an RGB array (bgr8 or rgb8)."""
    channels = {"bgr8": 3, "rgb8": 3}
    assert msg.encoding in channels, msg.encoding
    pixels = np.frombuffer(msg.data, dtype=np.uint8).reshape(msg.height, msg.step)[:, : msg.width * 3]
    pixels = pixels.reshape(msg.height, msg.width, 3)
    return pixels[:, :, ::-1] if msg.encoding == "bgr8" else pixels


def main():
    folder, tool_dir = sys.argv[1], sys.argv[2]
    timeout = float(sys.argv[3]) if len(sys.argv) > 3 else 120.0
    names = frame_names(folder)
    n = len(names)
    colours = [np.asarray(PilImage.open(os.path.join(folder, name + "_rgb.png")).convert("RGB"))
               for name in names]
    frame_of_stamp = {}  # stamp [ns] -> folder index, from the colour image's content
    labels = {"superpixels": {}, "segments": {}}  # kind -> stamp [ns] -> labels
    got = {"superpixels": {}, "segments": {}}  # kind -> folder index -> labels (first complete)
    lock = threading.Lock()
    done = threading.Event()

    def settle(stamp):
        index = frame_of_stamp.get(stamp)
        if index is None:
            return
        for kind in got:
            if stamp in labels[kind]:
                got[kind].setdefault(index, labels[kind].pop(stamp))
        if all(len(v) == n for v in got.values()):
            done.set()

    def on_colour(msg):
        rgb = colour_of(msg)
        index = next((i for i, c in enumerate(colours) if c.shape == rgb.shape and np.array_equal(c, rgb)),
                     None)
        with lock:
            if index is not None:
                frame_of_stamp[msg.header.stamp.to_nsec()] = index
                settle(msg.header.stamp.to_nsec())

    def callback(kind):
        def store(msg):
            with lock:
                labels[kind][msg.header.stamp.to_nsec()] = labels_of(msg).copy()
                settle(msg.header.stamp.to_nsec())
        return store

    rospy.init_node("same_results", anonymous=True)
    rospy.Subscriber("/camera/rgb/image_rect_color", Image, on_colour, queue_size=100)
    rospy.Subscriber("/camera/superpixels/labels", Image, callback("superpixels"), queue_size=100)
    rospy.Subscriber("/camera/segments/labels", Image, callback("segments"), queue_size=100)
    done.wait(timeout)
    equal = {"superpixels": 0, "segments": 0}
    compared = 0
    for i, name in enumerate(names):
        row = [name]
        for kind in ("superpixels", "segments"):
            path = os.path.join(tool_dir, f"{name}_{kind}.png")
            if i not in got[kind] or not os.path.exists(path):
                row.append(f"{kind}: missing")
                continue
            tool = np.asarray(PilImage.open(path)).astype(np.int64) - 1
            ros = got[kind][i].astype(np.int64)
            diff = int(np.count_nonzero(tool != ros)) if tool.shape == ros.shape else -1
            equal[kind] += diff == 0
            row.append(f"{kind}: {diff} pixels differ ({ros.max() + 1} labels)")
        compared += 1
        print("  ".join(row))
    print(f"frames: {n}; superpixel labels identical in {equal['superpixels']}, "
          f"segment labels identical in {equal['segments']}")
    sys.exit(0 if equal["superpixels"] == n and equal["segments"] == n else 1)


if __name__ == "__main__":
    main()
