#!/usr/bin/python3
"""Summarises the demo's recording: what each node produced, checked for frames and stamps.

Writes the first colour and depth frame as PNG next to the bag and prints one line per topic.
Exits 1 when a stream the demo is meant to produce is missing, or, given the text event file the
emulated eDVS streamed (second argument), when the bag does not start with its first events.
"""
import os
import sys

import numpy as np
import rosbag

EXPECTED = {
    "/camera/rgb/image_rect_color": "camera_rgb_optical_frame",
    "/camera/depth_registered/image_raw": "camera_rgb_optical_frame",
    "/camera/rgb/camera_info": "camera_rgb_optical_frame",
    "/camera/superpixels": "camera_rgb_optical_frame",
    "/camera/segmentation": "camera_rgb_optical_frame",
    "/edvs/events": "edvs_optical_frame",
    "/edvs/camera_info": "edvs_optical_frame",
}


def save_png(path, msg):
    import matplotlib
    matplotlib.use("Agg")
    import matplotlib.pyplot as plt
    data = np.frombuffer(msg.data, dtype=np.uint8 if msg.encoding == "bgr8" else "<u2")
    if msg.encoding == "bgr8":
        plt.imsave(path, data.reshape(msg.height, msg.width, 3)[:, :, ::-1])
    else:
        plt.imsave(path, data.reshape(msg.height, msg.width), cmap="viridis")


def read_text_events(path, limit):
    """(x, y) of the first `limit` events of a text event file (t x y p lines, # comments)."""
    events = []
    with open(path) as f:
        for line in f:
            fields = line.split()
            if not fields or fields[0].startswith("#"):
                continue
            events.append((int(fields[1]), int(fields[2])))
            if len(events) == limit:
                break
    return events


def first_recorded_index(streamed, recorded):
    """Index in `streamed` of the first recorded event (None if the recording matches nowhere)."""
    n = min(len(recorded), 20)
    for i in range(len(streamed) - n + 1):
        if streamed[i:i + n] == recorded[:n]:
            return i
    return None


def main(out, streamed_path=None):
    bag_path = os.path.join(out, "demo.bag")
    recorded_xy = []
    stats = {}
    events = 0
    first_event = last_event = None
    saved = set()
    diagnostics = None
    with rosbag.Bag(bag_path) as bag:
        for topic, msg, _ in bag.read_messages():
            if topic == "/diagnostics":
                for status in msg.status:
                    if "eDVS" in status.name:
                        diagnostics = status
                continue
            s = stats.setdefault(topic, {"count": 0, "frames": set(), "first": None, "last": None})
            s["count"] += 1
            s["frames"].add(msg.header.frame_id)
            stamp = msg.header.stamp.to_sec()
            s["first"] = stamp if s["first"] is None else s["first"]
            s["last"] = stamp
            if topic == "/edvs/events":
                events += len(msg.events)
                if len(recorded_xy) < 20:
                    recorded_xy += [(e.x, e.y) for e in msg.events[:20 - len(recorded_xy)]]
                if msg.events:
                    first_event = first_event or msg.events[0].ts.to_sec()
                    last_event = msg.events[-1].ts.to_sec()
            if topic in ("/camera/rgb/image_rect_color", "/camera/depth_registered/image_raw") and topic not in saved:
                save_png(os.path.join(out, topic.strip("/").replace("/", "_") + "_first.png"), msg)
                saved.add(topic)
    print(f"  ROS recording: {os.path.relpath(bag_path, os.path.dirname(out))}")
    ok = True
    for topic, frame in EXPECTED.items():
        s = stats.get(topic)
        if not s:
            print(f"  {topic}: MISSING")
            ok = False
            continue
        frames = ",".join(sorted(s["frames"]))
        span = s["last"] - s["first"]
        print(f"  {topic}: {s['count']} messages over {span:.2f} s, frame {frames}")
        ok &= s["frames"] == {frame}
    if events:
        print(f"  eDVS driver: {events} events published, {events / max(last_event - first_event, 1e-9):.0f} events/s")
    else:
        print("  eDVS driver: no events published")
        ok = False
    if diagnostics is not None:
        values = {kv.key: kv.value for kv in diagnostics.values}
        keep = ["events published", "dropped bytes", "reconnects"]
        extra = ", ".join(f"{k} {values[k]}" for k in keep if k in values)
        print(f"  eDVS diagnostics: {diagnostics.message}" + (f" ({extra})" if extra else ""))
    if streamed_path and events:
        if not os.path.isfile(streamed_path):
            print(f"  first events: cannot check, {streamed_path} is missing")
            ok = False
        else:
            index = first_recorded_index(read_text_events(streamed_path, 200000), recorded_xy)
            if index == 0:
                print("  first events: the bag starts with the first event the eDVS streamed")
            else:
                where = "nowhere in the stream" if index is None else f"at streamed event {index}"
                print(f"  first events: MISSING, the bag starts {where}")
                ok = False
    return 0 if ok else 1


if __name__ == "__main__":
    sys.exit(main(sys.argv[1], sys.argv[2] if len(sys.argv) > 2 else None))
