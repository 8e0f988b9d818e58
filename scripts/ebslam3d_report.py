#!/usr/bin/env python3
"""Runs the EB-SLAM-3D evaluation (thesis 8.4, table 8.1, fig. 8.12, B.15/B.16) and writes
docs/results/ebslam3d.md with its plots. Called by scripts/ebslam3d_experiment.sh.

Every hand-held TUM ground-truth path in shared/data/tum-groundtruth (freiburg1_xyz, _desk,
_room, freiburg2_xyz) drives the synthetic depth-event source (ebslam_experiment_ebslam3d), the
first DURATION seconds of each, SEEDS seeds (filter and scene), default and fast sets; then
sweeps of N, K, event share, voxel size and diffusion on freiburg1_desk.
"""
import argparse
import concurrent.futures as cf
import json
import os
import subprocess
import sys

import matplotlib

matplotlib.use("Agg")
import matplotlib.pyplot as plt  # noqa: E402

PATHS = ["freiburg1_xyz", "freiburg1_desk", "freiburg1_room", "freiburg2_xyz"]
DIVERGED_M = 0.10  # position RMSE above this counts as a divergence


def run(tool, gt, args, out_prefix=None):
    cmd = [tool, "--groundtruth", gt] + [str(a) for a in args]
    if out_prefix:
        cmd += ["--aligned-truth", out_prefix + "_errors.csv", "--map-xyz", out_prefix + "_map.xyz"]
    res = subprocess.run(cmd, capture_output=True, text=True, check=True)
    return json.loads(res.stdout)


def main():
    ap = argparse.ArgumentParser()
    ap.add_argument("--tool", required=True)
    ap.add_argument("--data", required=True, help="shared/data")
    ap.add_argument("--runs", required=True)
    ap.add_argument("--out", required=True, help="docs/results")
    ap.add_argument("--bench", help="Google Benchmark JSON of ebslam_ebslam3d_bench")
    ap.add_argument("--seeds", type=int, default=3)
    ap.add_argument("--duration", type=float, default=15.0)
    ap.add_argument("--sweep-duration", type=float, default=6.0)
    ap.add_argument("--jobs", type=int, default=2)
    ap.add_argument("--command", default="scripts/ebslam3d_experiment.sh")
    ap.add_argument("--source", default="dedvs", choices=["dedvs", "synthetic"])
    ap.add_argument("--sweep-seeds", type=int, default=2, help="sweeps on seeds 1..this")
    ap.add_argument("--from-results", action="store_true",
                    help="only write the page, from RUNS/results.jsonl (e.g. of an interrupted run)")
    a = ap.parse_args()
    os.makedirs(a.runs, exist_ok=True)
    fig_dir = os.path.join(a.out, "ebslam3d")
    os.makedirs(fig_dir, exist_ok=True)
    gt = {p: os.path.join(a.data, "tum-groundtruth", f"rgbd_dataset_{p}-groundtruth.txt") for p in PATHS}
    gt = {p: f for p, f in gt.items() if os.path.exists(f)}
    if not gt:
        sys.exit("no TUM ground truth found under " + a.data)

    if a.from_results:
        results = [json.loads(l) for l in open(os.path.join(a.runs, "results.jsonl"))]
        write_page(a, results, SWEEPS, "freiburg1_desk")
        return
    jobs = []
    for p in gt:
        for seed in range(1, a.seeds + 1):
            for preset in ["default", "fast"]:
                prefix = os.path.join(a.runs, f"{p}_{preset}_{seed}")
                jobs.append(("main", p, preset, seed, None,
                             ["--source", a.source, "--preset", preset, "--seed", seed, "--scene-seed", seed,
                              "--duration", a.duration], prefix))
    sweep_path = "freiburg1_desk" if "freiburg1_desk" in gt else next(iter(gt))
    sweeps = SWEEPS
    for name, values in sweeps.items():
        for flag, v in values:
            for seed in range(1, a.sweep_seeds + 1):
                jobs.append(("sweep", sweep_path, "default", seed, (name, v),
                             ["--source", a.source, flag, v, "--seed", seed, "--scene-seed", seed,
                              "--duration", a.sweep_duration], None))
    results = []
    with cf.ThreadPoolExecutor(max_workers=a.jobs) as ex:
        futs = {ex.submit(run, os.path.abspath(a.tool), gt[j[1]], j[5], j[6]): j for j in jobs}
        for f in cf.as_completed(futs):
            kind, p, preset, seed, sweep, _, prefix = futs[f]
            r = f.result()
            r.update(kind=kind, path=p, preset=preset, seed=seed, prefix=prefix,
                     sweep=sweep[0] if sweep else None, value=sweep[1] if sweep else None)
            results.append(r)
            with open(os.path.join(a.runs, "results.jsonl"), "a") as log:
                log.write(json.dumps(r) + "\n")
            print(kind, p, preset, seed, sweep, "rmse %.4f rtf %.2f" % (r["rmse_m"], r["realtime_factor"]),
                  flush=True)
    with open(os.path.join(a.runs, "results.json"), "w") as f:
        json.dump(results, f, indent=1)
    write_page(a, results, sweeps, sweep_path)


SWEEPS = {
    "N": [("-N", v) for v in [10, 25, 50, 100, 200]],
    "K": [("-K", v) for v in [10, 25, 50, 100, 200, 400]],
    "B": [("-B", v) for v in [1, 3, 10, 30]],
    "event share": [("--event-share", v) for v in [0.1, 0.25, 0.5, 1.0]],
    "voxel [m]": [("--voxel", v) for v in [0.005, 0.01, 0.02, 0.04]],
    "sigma position [m/event]": [("--sigma-position", v) for v in [3e-4, 1e-3, 3e-3]],
    "sigma rotation [rad/event]": [("--sigma-rotation", v) for v in [3e-4, 1e-3, 3e-3]],
}


def results_from_log(a):
    import ast
    out = []
    for line in open(a.from_log):
        parts = line.split()
        if not parts or parts[0] not in ("main", "sweep"):
            continue
        kind, p, preset, seed = parts[0], parts[1], parts[2], int(parts[3])
        head, tail = line.split(" rmse ")
        rmse, rtf = float(tail.split()[0]), float(tail.split()[2])
        sweep = None if kind == "main" else ast.literal_eval(head.split(" ", 4)[4])
        prefix = os.path.join(a.runs, f"{p}_{preset}_{seed}") if kind == "main" else None
        r = dict(kind=kind, path=p, preset=preset, seed=seed, rmse_m=rmse, realtime_factor=rtf,
                 sweep=sweep[0] if sweep else None, value=sweep[1] if sweep else None, prefix=prefix)
        if prefix and os.path.exists(prefix + "_errors.csv"):
            rows = [l.strip().split(",") for l in open(prefix + "_errors.csv")][1:]
            r["rotation_rmse_deg"] = (sum(float(x[2]) ** 2 for x in rows) / len(rows)) ** 0.5
        out.append(r)
    return out


def mean(xs):
    return sum(xs) / len(xs) if xs else float("nan")


def write_page(a, results, sweeps, sweep_path, partial=False):
    fig_dir = os.path.join(a.out, "ebslam3d")
    main_runs = [r for r in results if r["kind"] == "main"]
    lines = []
    w = lines.append
    w("# EB-SLAM-3D: six-DOF event-based SLAM on depth events (thesis 8.3-8.4)")
    w("")
    w(f"Regenerate: `{a.command}` (builds the core library, runs every path below, the sweeps and")
    w("the benchmark, and rewrites this page and its plots; about 15-25 min on a loaded 2-core machine).")
    w("")
    w("**Data.** The D-eDVS simulator (issue 27) was not on main when these runs started (it landed during them), so the")
    w("depth events come from the core library's own synthetic source (`synthetic_depth_events.h`):")
    w("a closed box room 1.5 m beyond each path's bounding box, its faces textured with random")
    w("rectangles and lines (3 per m^2, sampled every 1 cm); a 128x128 pinhole event sensor (f = 160 px)")
    w("moving along the TUM ground-truth camera path fires an event whenever an edge point's projection")
    w("enters another pixel, with the point's depth (noise 0.0015 D^2) back-projected through the pixel")
    w("centre, plus 2 % noise events at random pixels and depths. The room is convex (no occlusion), and")
    w("it is a geometric model of where events happen, not a DVS pixel model: the figures below say how")
    w("the filter behaves on this source, not on the thesis' real takes.")
    w("")
    w(f"**Runs.** Every hand-held TUM path ({', '.join(sorted(set(r['path'] for r in main_runs)))}), the first "
      f"{a.duration:g} s of each, seeds 1..{a.seeds} (the seed sets both the filter and the room), the default "
      "set (N 100, K 100, B 3, all events, 1 cm voxels) and the fast set (N 25, K 100, B 5, a quarter of the events).")
    w("Errors after the alignment of eq. 8.16-8.19 (rigid, with a time offset; `trajectory_evaluation.h`),")
    w("rotation error eq. 8.20 as an RMS in degrees; real-time factor = event-stream duration / CPU time of")
    w("the filter (one thread, `CLOCK_THREAD_CPUTIME_ID`); memory = peak of the voxel map plus particles")
    w(f"(map bound 24 MiB). A run 'diverged' if its RMSE exceeds {DIVERGED_M * 100:.0f} cm.")
    w("")
    w("**Tuning split.** The diffusion defaults (1e-3 m and 1e-3 rad per event) were chosen by hand on the")
    w("first 8-10 s of freiburg1_xyz, _desk and _room with scene seed 1; freiburg2_xyz and seeds 2-3 were not")
    w("looked at before this evaluation. The N/K/B defaults are the thesis' and were not tuned.")
    w("")
    if partial:
        w("**This evaluation was interrupted** (time limit of the session): the page is written from the")
        w("progress log of the runs that finished; the 'runs' column counts them, sweeps that did not run")
        w("are listed as such, and the per-run stream rate and peak memory were not recorded. The machine")
        w("ran at a load of 15-17 on its 2 cores during these runs, which lowers the CPU-time rates.")
        w("")
    w("## Table 8.1 analogue")
    w("")
    w("| path | runs | events/s (stream) | default RMSE [cm] (mean / worst) | rot. [deg] | speed [x real time] | fast RMSE [cm] (mean / worst) | fast speed | peak memory [MiB] | diverged (default / fast) |")
    w("|---|---|---|---|---|---|---|---|---|---|")
    for p in PATHS:
        d = [r for r in main_runs if r["path"] == p and r["preset"] == "default"]
        f = [r for r in main_runs if r["path"] == p and r["preset"] == "fast"]
        if not d:
            continue
        fmt_k = lambda xs: "%.0fk" % (mean(xs) / 1e3) if xs else "n/a"
        mem = [r["peak_memory_bytes"] for r in d + f if "peak_memory_bytes" in r]
        w("| %s | %d + %d | %s | %.2f / %.2f | %.2f | %.1f | %.2f / %.2f | %.1f | %s | %d / %d |" % (
            p, len(d), len(f), fmt_k([r["events_per_s_stream"] for r in d if "events_per_s_stream" in r]),
            100 * mean([r["rmse_m"] for r in d]), 100 * max(r["rmse_m"] for r in d),
            mean([r["rotation_rmse_deg"] for r in d]), mean([r["realtime_factor"] for r in d]),
            100 * mean([r["rmse_m"] for r in f]), 100 * max(r["rmse_m"] for r in f),
            mean([r["realtime_factor"] for r in f]),
            "%.1f" % (max(mem) / 2**20) if mem else "n/a",
            sum(r["rmse_m"] > DIVERGED_M for r in d), sum(r["rmse_m"] > DIVERGED_M for r in f)))
    w("")
    w("Thesis table 8.1 (real takes, 2013 hardware): default 3.1-13.4 cm at 1.4-2.5x real time, fast")
    w("4.0-13.3 cm at 16-27x, 14-27 MB.")
    w("")
    d_all = [r for r in main_runs if r["preset"] == "default"]
    f_all = [r for r in main_runs if r["preset"] == "fast"]
    w("## The issue's bars")
    w("")
    worst = max(r["rmse_m"] for r in d_all)
    w(f"- Accuracy, RMSE <= 3 cm on every run at the default set: worst {100 * worst:.2f} cm over {len(d_all)} runs -> "
      + ("**met**" if worst <= 0.03 else "**not met**") + f"; divergences: {sum(r['rmse_m'] > DIVERGED_M for r in d_all)} default, "
      f"{sum(r['rmse_m'] > DIVERGED_M for r in f_all)} fast.")
    w(f"- Speed, >= 20x real time at the default set: {min(r['realtime_factor'] for r in d_all):.1f}x to "
      f"{max(r['realtime_factor'] for r in d_all):.1f}x on these streams -> "
      + ("**met**" if min(r['realtime_factor'] for r in d_all) >= 20 else "**not met**")
      + f"; fast set >= 200x: {min(r['realtime_factor'] for r in f_all):.1f}x to {max(r['realtime_factor'] for r in f_all):.1f}x -> "
      + ("**met**" if min(r['realtime_factor'] for r in f_all) >= 200 else "**not met**") + ".")
    w("  The real-time factor is the processing rate (events/s) over the stream's event rate, and this source")
    w("  fires 30k-250k events/s depending on the path's speed; the benchmark below gives the rate itself.")
    mem = [r["peak_memory_bytes"] for r in main_runs if "peak_memory_bytes" in r]
    if mem:
        w(f"- Memory <= 30 MB per run: peak {max(mem) / 2**20:.1f} MiB (map bound 24 MiB; evictions per run in results.json).")
    else:
        w("- Memory <= 30 MB per run: the map is bounded at 24 MiB (map + particles stay below 24.1 MiB by")
        w("  construction; the benchmark's runs peak at the figure in its table). The per-run peaks were not")
        w("  recorded in this (interrupted) evaluation.")
    w("")
    # Trajectory plots.
    w("## Paths against ground truth (default set, seed 1)")
    w("")
    for p in PATHS:
        r = next((r for r in main_runs if r["path"] == p and r["preset"] == "default" and r["seed"] == 1), None)
        if not r:
            continue
        rows = [l.strip().split(",") for l in open(r["prefix"] + "_errors.csv")][1:]
        est = [(float(x[3]), float(x[4]), float(x[5])) for x in rows]
        gtp = [(float(x[6]), float(x[7]), float(x[8])) for x in rows]
        fig, ax = plt.subplots(1, 2, figsize=(10, 4.2))
        for k, (i, j) in enumerate([(0, 1), (0, 2)]):
            ax[k].plot([g[i] for g in gtp], [g[j] for g in gtp], "b-", lw=1, label="ground truth")
            ax[k].plot([e[i] for e in est], [e[j] for e in est], "r-", lw=1, label="EB-SLAM-3D (aligned)")
            ax[k].set_xlabel("xyz"[i] + " [m]")
            ax[k].set_ylabel("xyz"[j] + " [m]")
            ax[k].axis("equal")
        ax[0].legend()
        fig.suptitle(f"{p}: RMSE {100 * r['rmse_m']:.2f} cm, rotation {r['rotation_rmse_deg']:.2f} deg")
        fig.tight_layout()
        fig.savefig(os.path.join(fig_dir, f"path_{p}.png"), dpi=80)
        plt.close(fig)
        w(f"![{p}](ebslam3d/path_{p}.png)")
        w("")
    # Map plot.
    r = next((r for r in main_runs if r["path"] == "freiburg1_desk" and r["preset"] == "default" and r["seed"] == 1), None)
    if r and os.path.exists(r["prefix"] + "_map.xyz"):
        pts = [tuple(map(float, l.split())) for l in open(r["prefix"] + "_map.xyz")]
        pts = pts[:: max(1, len(pts) // 60000)]
        fig, ax = plt.subplots(1, 2, figsize=(10, 4.5))
        for k, (i, j) in enumerate([(0, 1), (0, 2)]):
            ax[k].scatter([q[i] for q in pts], [q[j] for q in pts], s=0.2, c="k", alpha=0.3)
            ax[k].set_xlabel("xyz"[i] + " [m] (map frame)")
            ax[k].set_ylabel("xyz"[j] + " [m]")
            ax[k].axis("equal")
        fig.suptitle("freiburg1_desk, default, seed 1: occurrence-map voxels with O > 1 (two projections)")
        fig.tight_layout()
        fig.savefig(os.path.join(fig_dir, "map_freiburg1_desk.png"), dpi=80)
        plt.close(fig)
        w("## Map")
        w("")
        w("![map](ebslam3d/map_freiburg1_desk.png)")
        w("")
    # Sweeps.
    w(f"## Parameter sweeps (fig. 8.12, B.15, B.16) on {sweep_path}, first {a.sweep_duration:g} s, seed 1")
    w("")
    w("Other parameters at the default set.")
    w("")
    names = list(sweeps)
    fig, axes = plt.subplots(len(names), 2, figsize=(9, 2.4 * len(names)))
    for row, name in enumerate(names):
        rs = [r for r in results if r["kind"] == "sweep" and r["sweep"] == name]
        vals = sorted(set(r["value"] for r in rs))
        if not vals:
            w(f"- {name}: not run in this evaluation.")
            w("")
            continue
        rm = [100 * mean([r["rmse_m"] for r in rs if r["value"] == v]) for v in vals]
        rt = [mean([r["realtime_factor"] for r in rs if r["value"] == v]) for v in vals]
        axes[row][0].plot(vals, rm, "o-")
        axes[row][0].set_ylabel("RMSE [cm]")
        axes[row][0].set_xlabel(name)
        axes[row][1].plot(vals, rt, "o-")
        axes[row][1].set_ylabel("x real time")
        axes[row][1].set_xlabel(name)
        for ax in axes[row]:
            if name != "event share":
                ax.set_xscale("log")
        w(f"| {name} | " + " | ".join(f"{v:g}" for v in vals) + " |")
        w("|---|" + "---|" * len(vals))
        w("| RMSE [cm] | " + " | ".join(f"{x:.2f}" for x in rm) + " |")
        w("| x real time | " + " | ".join(f"{x:.1f}" for x in rt) + " |")
        w("")
    fig.tight_layout()
    fig.savefig(os.path.join(fig_dir, "sweeps.png"), dpi=70)
    plt.close(fig)
    w("![sweeps](ebslam3d/sweeps.png)")
    w("")
    if a.bench and os.path.exists(a.bench):
        b = json.load(open(a.bench))
        w("## Benchmark (`ebslam_ebslam3d_bench`)")
        w("")
        w("Synthetic 4 s path (0.4 m, 0.35 rad turn, starting and ending at rest) in the synthetic room; CPU time of")
        w("the process; one core.")
        w("")
        w("| benchmark | events/s | stream events/s | x real time | thesis x real time | peak map [MiB] |")
        w("|---|---|---|---|---|---|")
        for bm in b["benchmarks"]:
            if bm.get("run_type") == "aggregate" and bm.get("aggregate_name") != "median":
                continue
            w("| %s | %.0fk | %.1fk | %.1f | %s | %.1f |" % (
                bm["name"], bm["events_per_s"] / 1e3, bm["stream_events_per_s"] / 1e3, bm["realtime_factor"],
                "%g" % bm["thesis_realtime_factor"] if bm["thesis_realtime_factor"] else "-", bm["peak_map_mib"]))
        w("")
    with open(os.path.join(a.out, "ebslam3d.md"), "w") as f:
        f.write("\n".join(lines) + "\n")


if __name__ == "__main__":
    main()
