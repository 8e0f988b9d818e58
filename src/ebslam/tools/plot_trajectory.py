#!/usr/bin/python3
"""Plots an evaluated trajectory: both paths in the x-y plane and the errors over time.

Input is the CSV written by `ebslam_evaluate_trajectory --csv` (aligned estimate and ground truth
per associated pose, position and rotation errors); optionally the full ground-truth TUM file
for the complete reference path.

  ebslam_evaluate_trajectory est.txt gt.txt --csv errors.csv
  tools/plot_trajectory.py errors.csv -o trajectory.png [--groundtruth gt.txt] [--title run]
"""

import argparse
import csv
import sys

import matplotlib

matplotlib.use("Agg")  # files only, no display needed
import matplotlib.pyplot as plt  # noqa: E402


def read_errors(path):
    columns = {}
    with open(path, newline="") as f:
        reader = csv.DictReader(f)
        required = ["t_s", "position_error_m", "rotation_error_deg", "est_x", "est_y", "gt_x", "gt_y"]
        missing = [c for c in required if c not in (reader.fieldnames or [])]
        if missing:
            raise ValueError(f"{path}: missing columns {missing}")
        for row in reader:
            for key, value in row.items():
                columns.setdefault(key, []).append(float(value))
    if not columns:
        raise ValueError(f"{path}: no rows")
    return columns


def read_tum_xy(path):
    xs, ys = [], []
    with open(path) as f:
        for line in f:
            fields = line.split()
            if not fields or fields[0].startswith("#"):
                continue
            xs.append(float(fields[1]))
            ys.append(float(fields[2]))
    return xs, ys


def rmse(values):
    return (sum(v * v for v in values) / len(values)) ** 0.5


def main():
    parser = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    parser.add_argument("csv", help="per-pose errors from ebslam_evaluate_trajectory --csv")
    parser.add_argument("-o", "--output", default="trajectory.png", help="image file to write")
    parser.add_argument("--groundtruth", help="full ground-truth TUM file (drawn as reference path)")
    parser.add_argument("--title", default="", help="figure title")
    args = parser.parse_args()

    try:
        e = read_errors(args.csv)
    except (OSError, ValueError) as err:
        print(f"error: {err}", file=sys.stderr)
        return 1
    t0 = e["t_s"][0]
    t = [v - t0 for v in e["t_s"]]

    fig, (ax_path, ax_err) = plt.subplots(1, 2, figsize=(13, 5.5))
    if args.groundtruth:
        gx, gy = read_tum_xy(args.groundtruth)
        ax_path.plot(gx, gy, color="0.75", linewidth=1.0, label="ground truth (full)")
    ax_path.plot(e["gt_x"], e["gt_y"], color="tab:blue", linewidth=1.5, label="ground truth")
    ax_path.plot(e["est_x"], e["est_y"], color="tab:red", linewidth=1.0, label="estimate (aligned)")
    ax_path.plot(e["gt_x"][0], e["gt_y"][0], "ko", markersize=4, label="start")
    ax_path.set_xlabel("x [m]")
    ax_path.set_ylabel("y [m]")
    ax_path.set_aspect("equal", adjustable="datalim")
    ax_path.grid(True, alpha=0.3)
    ax_path.legend(loc="best", fontsize="small")
    ax_path.set_title("paths in the x-y plane")

    pos_cm = [100.0 * v for v in e["position_error_m"]]
    ax_err.plot(t, pos_cm, color="tab:red", linewidth=1.0,
                label=f"position (RMSE {100.0 * rmse(e['position_error_m']):.2f} cm)")
    ax_err.set_xlabel(f"time since {t0:.3f} s [s]")
    ax_err.set_ylabel("position error [cm]")
    ax_err.grid(True, alpha=0.3)
    ax_rot = ax_err.twinx()
    ax_rot.plot(t, e["rotation_error_deg"], color="tab:green", linewidth=0.8,
                label=f"rotation (RMSE {rmse(e['rotation_error_deg']):.2f} deg)")
    ax_rot.set_ylabel("rotation error [deg]")
    lines = ax_err.get_lines() + ax_rot.get_lines()
    ax_err.legend(lines, [line.get_label() for line in lines], loc="upper left", fontsize="small")
    ax_err.set_title("error over time")

    if args.title:
        fig.suptitle(args.title)
    fig.tight_layout()
    fig.savefig(args.output, dpi=120)
    print(f"wrote {args.output}")
    return 0


if __name__ == "__main__":
    sys.exit(main())
