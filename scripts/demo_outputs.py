#!/usr/bin/python3
"""Writes what `make demo` shows from the topics the pipeline published (recorded in a bag).

  demo_outputs.py <output bag> <output folder>

- superpixels_overlay.png, segments_overlay.png: the middle frame's overlays (camera/superpixels/overlay,
  camera/segments/overlay);
- ebslam_map.png: the last picture of the SLAM map (ebslam/map/image);
- trajectory.tum, ground_truth.tum: the SLAM pose topic and the simulator's ground truth, TUM format;
- topics.txt: per topic the message count, rate over its stamps and frame ids.
Exits 1 when a topic the demo must produce is missing.
"""
import os
import sys

import numpy as np
import rosbag

REQUIRED = [
    "/camera/superpixels", "/camera/superpixels/labels", "/camera/superpixels/overlay",
    "/camera/segmentation", "/camera/segments/labels", "/camera/segments/overlay",
    "/ebslam/pose", "/ebslam/path", "/ebslam/map", "/ebslam/map/image", "/edvs/event_image",
    "/ground_truth/pose",
]
PICTURES = {"/camera/superpixels/overlay": "superpixels_overlay.png",
            "/camera/segments/overlay": "segments_overlay.png",
            "/edvs/event_image": "event_image.png"}


def image_array(msg):
    channels = {"bgr8": 3, "rgb8": 3, "mono8": 1}[msg.encoding]
    data = np.frombuffer(msg.data, dtype=np.uint8).reshape(msg.height, msg.step)
    data = data[:, : msg.width * channels].reshape(msg.height, msg.width, channels)
    if msg.encoding == "bgr8":
        data = data[:, :, ::-1]
    return data[:, :, 0] if channels == 1 else data


def save_png(path, msg):
    import matplotlib
    matplotlib.use("Agg")
    import matplotlib.pyplot as plt
    image = image_array(msg)
    plt.imsave(path, image, cmap="gray" if image.ndim == 2 else None)


def pose_line(stamp, p, q):
    return f"{stamp:.6f} {p.x:.6f} {p.y:.6f} {p.z:.6f} {q.x:.6f} {q.y:.6f} {q.z:.6f} {q.w:.6f}\n"


def main(bag_path, out):
    stats, images = {}, {}
    map_image = None
    poses, truth = [], []
    with rosbag.Bag(bag_path) as bag:
        for topic, msg, recorded in bag.read_messages():
            header = getattr(msg, "header", None)
            s = stats.setdefault(topic, {"count": 0, "frames": set(), "stamps": []})
            s["count"] += 1
            if header is not None:
                s["frames"].add(header.frame_id)
                s["stamps"].append(header.stamp.to_sec())
            elif getattr(msg, "transforms", None):
                # tf2_msgs/TFMessage (/tf, /tf_static) has no header: its transforms have theirs.
                s["frames"].update(t.header.frame_id for t in msg.transforms)
                s["stamps"].append(max(t.header.stamp.to_sec() for t in msg.transforms))
            else:
                s["stamps"].append(recorded.to_sec())
            if topic in PICTURES:
                images.setdefault(topic, []).append(msg)
            elif topic == "/ebslam/map/image":
                map_image = msg
            elif topic == "/ebslam/pose":
                poses.append(pose_line(header.stamp.to_sec(), msg.pose.pose.position, msg.pose.pose.orientation))
            elif topic == "/ground_truth/pose":
                truth.append(pose_line(header.stamp.to_sec(), msg.pose.position, msg.pose.orientation))
    for topic, msgs in images.items():
        save_png(os.path.join(out, PICTURES[topic]), msgs[len(msgs) // 2])
    if map_image is not None:
        save_png(os.path.join(out, "ebslam_map.png"), map_image)
    with open(os.path.join(out, "trajectory.tum"), "w") as f:
        f.writelines(poses)
    with open(os.path.join(out, "ground_truth.tum"), "w") as f:
        f.writelines(truth)
    ok = True
    with open(os.path.join(out, "topics.txt"), "w") as f:
        for topic in sorted(set(stats) | set(REQUIRED)):
            s = stats.get(topic)
            if s is None:
                line = f"  {topic}: MISSING"
                ok &= topic not in REQUIRED
            else:
                stamps = sorted(s["stamps"])
                span = (stamps[-1] - stamps[0]) if len(stamps) > 1 else 0.0
                rate = (len(stamps) - 1) / span if span > 0 else 0.0
                frames = ",".join(sorted(s["frames"])) or "-"
                line = f"  {topic}: {s['count']} messages, {rate:.1f} Hz, frame {frames}"
                ok &= not (topic in REQUIRED and s["count"] == 0)
            print(line)
            f.write(line + "\n")
    return 0 if ok else 1


if __name__ == "__main__":
    sys.exit(main(sys.argv[1], sys.argv[2]))
