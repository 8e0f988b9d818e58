#!/usr/bin/env python3
"""Markdown tables of ebslam_experiment_localisation's runs.csv (docs/results/localisation.md).

Usage: localisation_report.py <folder with runs.csv and covariance.csv> [--tune TRAJECTORY --tune-seeds 1,2]
Rows are split into the tuning half (the trajectory and seeds the parameters were chosen on) and the
held-out rest; the bars are read on the held-out rows.
"""
import argparse
import csv
import math
import statistics
import sys
from pathlib import Path


def fnum(v):
    try:
        return float(v)
    except ValueError:
        return math.nan


def main():
    ap = argparse.ArgumentParser()
    ap.add_argument("folder")
    ap.add_argument("--tune", default="freiburg2_pioneer_360")
    ap.add_argument("--tune-seeds", default="1,2")
    a = ap.parse_args()
    rows = list(csv.DictReader(open(Path(a.folder) / "runs.csv")))
    tune_seeds = {int(s) for s in a.tune_seeds.split(",")}

    def half(r):
        return "tuning" if r["trajectory"] == a.tune and int(r["seed"]) in tune_seeds else "held-out"

    out = sys.stdout
    # Global localisation.
    out.write("| set | runs | converged within 10 s of motion | median (motion) | max (motion) | "
              "median (wall clock) | false tracking > 2 s | longest false tracking | real time (min) |\n"
              "|---|---|---|---|---|---|---|---|---|\n")
    for h in ("tuning", "held-out"):
        g = [r for r in rows if r["mode"] == "global" and half(r) == h]
        if not g:
            continue
        wall = [fnum(r["converged_s"]) for r in g if not math.isnan(fnum(r["converged_s"]))]
        times = [fnum(r["converged_motion_s"]) for r in g]
        ok = [t for t in times if not math.isnan(t) and t <= 10.0]
        false = [fnum(r["false_tracking_s"]) for r in g]
        rt = min(fnum(r["events_per_s"]) / fnum(r["event_rate"]) for r in g)
        conv = [t for t in times if not math.isnan(t)]
        out.write(f"| {h} | {len(g)} | {len(ok)}/{len(g)} ({100 * len(ok) / len(g):.0f} %) | "
                  f"{statistics.median(conv) if conv else math.nan:.2f} s | "
                  f"{max(conv) if conv else math.nan:.2f} s | "
                  f"{statistics.median(wall) if wall else math.nan:.2f} s | {sum(f > 2.0 for f in false)} | "
                  f"{max(false):.2f} s | {rt:.1f}x |\n")
    out.write("\n")
    # Kidnapping.
    out.write("| set | runs | jump | recovered within 15 s | median time | max time | real time (min) |\n"
              "|---|---|---|---|---|---|---|\n")
    for h in ("tuning", "held-out"):
        k = [r for r in rows if r["mode"] == "kidnap" and half(r) == h]
        if not k:
            continue
        times = [fnum(r["converged_s"]) for r in k]  # wall clock after the kidnap
        ok = [t for t in times if not math.isnan(t) and t <= 15.0]
        jumps = [fnum(r["extra"]) for r in k]
        rt = min(fnum(r["events_per_s"]) / fnum(r["event_rate"]) for r in k)
        conv = [t for t in times if not math.isnan(t)]
        out.write(f"| {h} | {len(k)} | {min(jumps):.1f}-{max(jumps):.1f} m | {len(ok)}/{len(k)} "
                  f"({100 * len(ok) / len(k):.0f} %) | {statistics.median(conv) if conv else math.nan:.2f} s | "
                  f"{max(conv) if conv else math.nan:.2f} s | {rt:.1f}x |\n")
    out.write("\n")
    # Tracking, odometry, turns: RMSE per trajectory and setting.
    def rms(values):
        return math.sqrt(sum(v * v for v in values) / len(values)) if values else math.nan

    out.write("| trajectory | set | mode | N | odometry | runs | position RMSE | rotation RMSE | "
              "kidnap false alarms | worst error | real time (min) |\n"
              "|---|---|---|---|---|---|---|---|---|---|---|\n")
    keys = []
    for r in rows:
        if r["mode"] in ("tracking", "tracking_detector", "odometry", "turn"):
            key = (r["trajectory"], half(r), r["mode"], r["particles"], r["odometry"])
            if key not in keys:
                keys.append(key)
    for key in keys:
        g = [r for r in rows if (r["trajectory"], half(r), r["mode"], r["particles"], r["odometry"]) == key]
        pos = rms([fnum(r["position_rmse_m"]) for r in g])
        rot = rms([fnum(r["rotation_rmse_deg"]) for r in g])
        alarms = sum(int(r["recoveries"]) for r in g)
        worst = max(fnum(r["extra"]) for r in g) if key[2] == "turn" else math.nan
        rt = min(fnum(r["events_per_s"]) / fnum(r["event_rate"]) for r in g)
        out.write(f"| {key[0]} | {key[1]} | {key[2]} | {key[3]} | {'yes' if key[4] == '1' else 'no'} | "
                  f"{len(g)} | {100 * pos:.2f} cm | {rot:.2f} deg | {alarms} | "
                  f"{'' if math.isnan(worst) else f'{100 * worst:.1f} cm'} | {rt:.0f}x |\n")
    cov = Path(a.folder) / "covariance.csv"
    if cov.exists():
        out.write("\n| set | poses | scale | floor | floor (heading) | NEES in band, unscaled | "
                  "NEES in band |\n|---|---|---|---|---|---|---|\n")
        for r in csv.DictReader(open(cov)):
            out.write(f"| {r['set']} | {r['poses']} | {fnum(r['scale']):g} | {1000 * fnum(r['floor_m']):.1f} mm | "
                      f"{fnum(r['floor_deg']):.2f} deg | {100 * fnum(r['in_band_raw']):.1f} % | "
                      f"{100 * fnum(r['in_band']):.1f} % |\n")


if __name__ == "__main__":
    main()
