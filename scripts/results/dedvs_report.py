#!/usr/bin/env python3
"""Rewrites the generated blocks of docs/results/dedvs.md (simulator output, fusion and calibration
tables, speed, pictures) from the outputs of scripts/results/dedvs_experiment.sh; the prose is
hand-written."""
import argparse
import os
import re
import sys

import matplotlib

matplotlib.use("Agg")
import matplotlib.pyplot as plt  # noqa: E402
import numpy as np  # noqa: E402

sys.path.insert(0, os.path.dirname(os.path.abspath(__file__)))
import pagegen  # noqa: E402


def read_events(path):
    data = open(path, "rb").read()
    record = np.dtype([("t", "<i8"), ("x", "<u2"), ("y", "<u2"), ("z", "<f4")])
    rec = np.frombuffer(data[24:], dtype=record)
    return rec["t"], rec["x"] & 0x7FFF, rec["y"] & 0x3FFF, rec["x"] >> 15, rec["z"]


def frames_picture(runs, out):
    """An event frame (30 ms) beside the depth and colour frame at its time."""
    t, x, y, p, _ = read_events(os.path.join(runs, "desk", "events.bin"))
    frames = [line.split() for line in open(os.path.join(runs, "desk", "frames.txt")) if line[0] != "#"]
    index = len(frames) // 2
    t_frame = float(frames[index][1])
    sel = (t >= t_frame * 1e6 - 15000) & (t < t_frame * 1e6 + 15000)
    image = np.zeros((128, 128))
    np.add.at(image, (y[sel], x[sel]), np.where(p[sel] == 1, 1, -1))
    depth = plt.imread(os.path.join(runs, "desk", "depth", "%06d.png" % index)) * 65.535
    colour = plt.imread(os.path.join(runs, "desk", "colour", "%06d.png" % index))
    fig, axes = plt.subplots(1, 3, figsize=(15, 4.4))
    axes[0].imshow(np.clip(image, -2, 2), cmap="gray", interpolation="nearest")
    axes[0].set_title("eDVS events, 30 ms (%d events; white ON, black OFF)" % sel.sum())
    shown = axes[1].imshow(np.where(depth > 0, depth, np.nan), cmap="jet", vmin=0.5, vmax=4.0)
    axes[1].set_title("depth frame 320x240 (holes white)")
    fig.colorbar(shown, ax=axes[1], label="depth [m]")
    axes[2].imshow(colour)
    axes[2].set_title("registered colour")
    for axis in axes:
        axis.set_xticks([])
        axis.set_yticks([])
    fig.tight_layout()
    fig.savefig(os.path.join(out, "dedvs_frames.png"), dpi=80)
    plt.close(fig)
    return "![event frame, depth frame and colour](dedvs_frames.png)"


def fused_picture(runs, out):
    """50 ms of fused events in the image and as 3D points."""
    fused = np.loadtxt(os.path.join(runs, "fused.txt"))
    ok = np.isfinite(fused[:, 3])
    fig = plt.figure(figsize=(13, 5))
    axis = fig.add_subplot(1, 2, 1)
    axis.scatter(fused[ok, 1], fused[ok, 2], c=fused[ok, 3], cmap="jet_r", s=3, vmin=0.5, vmax=4.0)
    axis.scatter(fused[~ok, 1], fused[~ok, 2], c="lightgrey", s=2)
    axis.set_xlim(0, 127)
    axis.set_ylim(127, 0)
    axis.set_aspect("equal")
    axis.set_title("50 ms of fused events (colour: depth, red near; grey: no depth)")
    axis = fig.add_subplot(1, 2, 2, projection="3d")
    axis.scatter(fused[ok, 5], fused[ok, 7], -fused[ok, 6], c=fused[ok, 3], cmap="jet_r", s=2,
                 vmin=0.5, vmax=4.0)
    axis.set_xlabel("x [m]")
    axis.set_ylabel("z (depth) [m]")
    axis.set_zlabel("-y [m]")
    axis.set_title("the same events as 3D points (eDVS frame)")
    axis.view_init(elev=20, azim=-70)
    fig.tight_layout()
    fig.savefig(os.path.join(out, "dedvs_fused.png"), dpi=80)
    plt.close(fig)
    return "![fused events](dedvs_fused.png)"


def speed_text(runs):
    """The fusion's and the event file reader's CPU time per event from the bench's console output."""
    bench = [line for line in open(os.path.join(runs, "bench.txt")) if line.startswith("BM_")]
    ns = {}
    for line in bench:
        m = re.match(r"(BM_\w+)_median\s+[\d.]+ \w+\s+[\d.]+ \w+\s+\d+ items_per_second=([\d.]+)([kMG]?)/s", line)
        if m:
            scale = {"": 1, "k": 1e3, "M": 1e6, "G": 1e9}[m.group(3)]
            ns[m.group(1)] = 1e9 / (float(m.group(2)) * scale)
    table = re.search(r"table_bytes=([\d.]+[kM]?)", "".join(bench))
    samples = re.search(r"samples_per_ray=([\d.]+)", "".join(bench))
    return f"""fusion {ns.get('BM_DedvsFuseEvent', float('nan')):.0f} ns per event, reading the same events from
the project's binary event file {ns.get('BM_ReadEventFile', float('nan')):.0f} ns per event.
Ray table: {table.group(1) if table else '?'} bytes, {samples.group(1) if samples else '?'} depth
pixels per eDVS ray (0.4-5 m, 320 x 240)."""


def main():
    parser = argparse.ArgumentParser()
    parser.add_argument("runs")
    parser.add_argument("--out", required=True)
    parser.add_argument("--command", default="scripts/results/dedvs_experiment.sh")
    args = parser.parse_args()
    runs, out = args.runs, args.out
    os.makedirs(out, exist_ok=True)
    simulate = open(os.path.join(runs, "simulate.txt")).read().strip()
    blocks = {"reproduce": f"`{args.command}`",
              "simulate": f"```\n{simulate}\n```",
              "frames": frames_picture(runs, out),
              "fusion": open(os.path.join(runs, "fusion.md")).read().strip(),
              "fused": fused_picture(runs, out),
              "speed": speed_text(runs)}
    calibration = os.path.join(runs, "calibration.md")
    if os.path.exists(calibration):
        blocks["calibration"] = open(calibration).read().strip()
    pagegen.update_page(os.path.join(out, "dedvs.md"), blocks)


if __name__ == "__main__":
    main()
