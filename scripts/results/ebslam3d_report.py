#!/usr/bin/env python3
"""Runs the EB-SLAM-3D evaluation (thesis 8.4, table 8.1, fig. 8.12, B.15/B.16) and writes
docs/results/ebslam3d.md with its plots. Called by scripts/results/ebslam3d_experiment.sh.

Every hand-held TUM ground-truth path in shared/data/tum-groundtruth (freiburg1_xyz, _desk,
_room, freiburg2_xyz) drives the D-eDVS simulator and depth fusion (ebslam_experiment_ebslam3d
--source dedvs; --source synthetic for the synthetic source), the first DURATION seconds of each,
SEEDS seeds (filter and scene), default and fast sets; then sweeps of N, K, B, event share, voxel
size and diffusion on freiburg1_desk seeds 1..SWEEP_SEEDS (the tuning half). The page's prose is
hand-written; this script rewrites its generated blocks (tables, plots, the reproduce command).
`--from-results` regenerates them from RUNS/results.jsonl alone (docs/results/ebslam3d/ keeps a copy).
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

sys.path.insert(0, os.path.dirname(os.path.abspath(__file__)))
import pagegen  # noqa: E402

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
    ap.add_argument("--command", default="scripts/results/ebslam3d_experiment.sh")
    ap.add_argument("--source", default="dedvs", choices=["dedvs", "synthetic"])
    ap.add_argument("--cut", default="", help="what was not run (printed on the page)")
    ap.add_argument("--check-k", type=int, help="only run the default set with this K on the held-out half "
                    "(appended to RUNS/results.jsonl as kind 'tuned'; then --from-results)")
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
    if a.check_k is not None:
        # A K chosen on the tuning half (the sweep), default set otherwise, on the held-out half.
        jobs = [("tuned", p, "default", seed, ("K", a.check_k),
                 ["--source", a.source, "--preset", "default", "-K", a.check_k, "--seed", seed,
                  "--scene-seed", seed, "--duration", a.duration], None)
                for p in gt for seed in range(1, a.seeds + 1)
                if held_out({"path": p, "seed": seed})]
        run_jobs(a, gt, jobs)
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
    results = run_jobs(a, gt, jobs)
    with open(os.path.join(a.runs, "results.json"), "w") as f:
        json.dump(results, f, indent=1)
    write_page(a, results, sweeps, sweep_path)


def run_jobs(a, gt, jobs):
    """Runs the jobs, appending each result to RUNS/results.jsonl as it finishes."""
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
    return results


SWEEPS = {
    "N": [("-N", v) for v in [10, 25, 50, 100, 200]],
    "K": [("-K", v) for v in [10, 25, 50, 100, 200, 400]],
    "B": [("-B", v) for v in [1, 3, 10, 30]],
    "event share": [("--event-share", v) for v in [0.1, 0.25, 0.5, 1.0]],
    "voxel [m]": [("--voxel", v) for v in [0.005, 0.01, 0.02, 0.04]],
    "sigma position [m/event]": [("--sigma-position", v) for v in [3e-4, 1e-3, 3e-3]],
    "sigma rotation [rad/event]": [("--sigma-rotation", v) for v in [3e-4, 1e-3, 3e-3]],
}


def mean(xs):
    return sum(xs) / len(xs) if xs else float("nan")


def held_out(r):
    """The sweeps (the only data any value below was read from) ran on freiburg1_desk seeds 1-2."""
    return not (r["path"] == "freiburg1_desk" and r["seed"] in (1, 2))


def table_8_1_blocks(a, main_runs):
    """The table 8.1 analogue (per path, all, held-out) and the RMSE of every run."""
    lines = []
    w = lines.append
    w("| path | runs | events/s (stream, with depth) | depth kept | default RMSE [cm] (mean / worst) | rot. [deg] | speed [x real time] | fast RMSE [cm] (mean / worst) | fast rot. [deg] | fast speed | map + particles [MiB] | peak RSS [MiB] | diverged (default / fast) |")
    w("|---|---|---|---|---|---|---|---|---|---|---|---|---|")

    def row(name, d, f):
        mem = [r["peak_memory_bytes"] for r in d + f if "peak_memory_bytes" in r]
        rss = [r["peak_rss_bytes"] for r in d + f if "peak_rss_bytes" in r]
        kept = [r["events"] / r["simulated_events"] for r in d if r.get("simulated_events")]
        fmt = lambda xs, f="%.2f / %.2f": (f % (100 * mean(xs), 100 * max(xs))) if xs else "n/a"
        w("| %s | %d + %d | %s | %s | %s | %.2f | %.1f | %s | %s | %s | %s | %s | %d / %d |" % (
            name, len(d), len(f),
            "%.0fk" % (mean([r["events_per_s_stream"] for r in d]) / 1e3) if d else "n/a",
            "%.0f %%" % (100 * mean(kept)) if kept else "n/a",
            fmt([r["rmse_m"] for r in d]), mean([r["rotation_rmse_deg"] for r in d]),
            mean([r["realtime_factor"] for r in d]),
            fmt([r["rmse_m"] for r in f]),
            "%.2f" % mean([r["rotation_rmse_deg"] for r in f]) if f else "n/a",
            "%.1f" % mean([r["realtime_factor"] for r in f]) if f else "n/a",
            "%.1f" % (max(mem) / 2**20) if mem else "n/a",
            "%.0f" % (max(rss) / 2**20) if rss else "n/a",
            sum(r["rmse_m"] > DIVERGED_M for r in d), sum(r["rmse_m"] > DIVERGED_M for r in f)))

    for p in PATHS:
        d = [r for r in main_runs if r["path"] == p and r["preset"] == "default"]
        f = [r for r in main_runs if r["path"] == p and r["preset"] == "fast"]
        if d or f:
            row(p, d, f)
    d_all = [r for r in main_runs if r["preset"] == "default"]
    f_all = [r for r in main_runs if r["preset"] == "fast"]
    row("all", d_all, f_all)
    row("held-out", [r for r in d_all if held_out(r)], [r for r in f_all if held_out(r)])
    per_run = "Per run (default / fast, seeds in order): " + "; ".join(
        "%s %s" % (p, " ".join("%.1f/%.1f" % tuple(
            100 * next((r["rmse_m"] for r in main_runs if r["path"] == p and r["preset"] == pr and r["seed"] == s),
                       float("nan")) for pr in ("default", "fast")) for s in range(1, a.seeds + 1)))
        for p in PATHS if any(r["path"] == p for r in main_runs)) + " cm."
    return {"table-8-1": lines, "per-run": per_run}


def tuned_block(tuned, d_all):
    """The K chosen on the tuning half against K = 100 on the held-out half."""
    k = tuned[0]["value"]
    lines = []
    w = lines.append
    w("| path | runs | RMSE K = 100 [cm] (mean / worst) | RMSE K = %g [cm] (mean / worst) | rot. K = %g [deg] | speed K = %g [x real time] | diverged K = 100 / K = %g |" % (k, k, k, k))
    w("|---|---|---|---|---|---|---|")
    for p in PATHS + ["all held-out"]:
        t = [r for r in tuned if p == "all held-out" or r["path"] == p]
        if not t:
            continue
        keys = {(r["path"], r["seed"]) for r in t}
        d = [r for r in d_all if (r["path"], r["seed"]) in keys]
        w("| %s | %d | %.2f / %.2f | %.2f / %.2f | %.2f | %.1f | %d / %d |" % (
            p, len(t), 100 * mean([r["rmse_m"] for r in d]), 100 * max(r["rmse_m"] for r in d),
            100 * mean([r["rmse_m"] for r in t]), 100 * max(r["rmse_m"] for r in t),
            mean([r["rotation_rmse_deg"] for r in t]), mean([r["realtime_factor"] for r in t]),
            sum(r["rmse_m"] > DIVERGED_M for r in d), sum(r["rmse_m"] > DIVERGED_M for r in t)))
    w("")
    t_all = [r["rmse_m"] for r in tuned]
    same = {(t["path"], t["seed"]) for t in tuned}
    d_same = [r["rmse_m"] for r in d_all if (r["path"], r["seed"]) in same]
    better = sum(t < d for t, d in zip(
        [r["rmse_m"] for r in sorted(tuned, key=lambda r: (r["path"], r["seed"]))],
        [r["rmse_m"] for r in sorted([r for r in d_all if (r["path"], r["seed"]) in same],
                                     key=lambda r: (r["path"], r["seed"]))]))
    w(f"Held-out mean RMSE {100 * mean(t_all):.2f} cm with K = {k:g} against {100 * mean(d_same):.2f} cm "
      f"with K = 100; K = {k:g} is better on {better} of {len(t_all)} runs.")
    return {"tuned": lines}


def summary_block(main_runs):
    """Accuracy, speed and memory of the main runs in a few lines."""
    d_all = [r for r in main_runs if r["preset"] == "default"]
    f_all = [r for r in main_runs if r["preset"] == "fast"]
    lines = []
    w = lines.append
    worst = max(r["rmse_m"] for r in d_all)
    w(f"- Position RMSE at the default set: worst {100 * worst:.2f} cm over {len(d_all)} runs, "
      f"{sum(r['rmse_m'] <= 0.03 for r in d_all)} of {len(d_all)} within 3 cm; divergences: "
      f"{sum(r['rmse_m'] > DIVERGED_M for r in d_all)} default, {sum(r['rmse_m'] > DIVERGED_M for r in f_all)} fast.")
    w(f"- Real time: {min(r['realtime_factor'] for r in d_all):.1f}x to {max(r['realtime_factor'] for r in d_all):.1f}x "
      f"at the default set, {min(r['realtime_factor'] for r in f_all):.1f}x to "
      f"{max(r['realtime_factor'] for r in f_all):.1f}x at the fast set. The filter processes "
      f"{min(r['events_per_s'] for r in d_all) / 1e3:.0f}k-{max(r['events_per_s'] for r in d_all) / 1e3:.0f}k events/s "
      f"(default) and {min(r['events_per_s'] for r in f_all) / 1e3:.0f}k-{max(r['events_per_s'] for r in f_all) / 1e3:.0f}k "
      f"events/s (fast, counting every streamed event); the simulator streams "
      f"{min(r['events_per_s_stream'] for r in d_all) / 1e3:.0f}k-{max(r['events_per_s_stream'] for r in d_all) / 1e3:.0f}k "
      "events/s with a depth.")
    mem = [r["peak_memory_bytes"] for r in main_runs if "peak_memory_bytes" in r]
    rss = [r["peak_rss_bytes"] for r in main_runs if "peak_rss_bytes" in r]
    if mem:
        w(f"- Memory: map + particles peak at {max(mem) / 2**20:.1f} MiB"
          + (f"; the whole process (simulator included) at {max(rss) / 2**20:.0f} MiB RSS." if rss else "."))
    return {"summary": lines}


def path_plots(main_runs, fig_dir):
    """Estimated against true path per TUM path (default, seed 1); {} without the runs' files."""
    lines = []
    for p in PATHS:
        r = next((r for r in main_runs if r["path"] == p and r["preset"] == "default" and r["seed"] == 1), None)
        if not r or not r.get("prefix") or not os.path.exists(r["prefix"] + "_errors.csv"):
            continue
        rows = [l.strip().split(",") for l in open(r["prefix"] + "_errors.csv")][1:]
        est = [(float(x[3]), float(x[4]), float(x[5])) for x in rows]
        gtp = [(float(x[6]), float(x[7]), float(x[8])) for x in rows]
        fig, ax = plt.subplots(1, 2, figsize=(10, 4.2))
        for k, (i, j) in enumerate([(0, 1), (0, 2)]):
            ax[k].plot([g[i] for g in gtp], [g[j] for g in gtp], "b-", lw=1, label="ground truth (eDVS)")
            ax[k].plot([e[i] for e in est], [e[j] for e in est], "r-", lw=1, label="EB-SLAM-3D (aligned)")
            ax[k].set_xlabel("xyz"[i] + " [m]")
            ax[k].set_ylabel("xyz"[j] + " [m]")
            ax[k].axis("equal")
        ax[0].legend()
        fig.suptitle(f"{p}: RMSE {100 * r['rmse_m']:.2f} cm, rotation {r['rotation_rmse_deg']:.2f} deg")
        fig.tight_layout()
        fig.savefig(os.path.join(fig_dir, f"path_{p}.png"), dpi=80)
        plt.close(fig)
        lines += [f"![{p}](ebslam3d/path_{p}.png)", ""]
    return {"paths": lines} if lines else {}


def map_plot(main_runs, fig_dir):
    """Occurrence-map voxels of freiburg1_desk (default, seed 1); {} without the run's map."""
    r = next((r for r in main_runs if r["path"] == "freiburg1_desk" and r["preset"] == "default" and r["seed"] == 1), None)
    if not (r and r.get("prefix") and os.path.exists(r["prefix"] + "_map.xyz")):
        return {}
    pts = [tuple(map(float, l.split())) for l in open(r["prefix"] + "_map.xyz")]
    pts = pts[:: max(1, len(pts) // 60000)]
    fig, ax = plt.subplots(1, 2, figsize=(10, 4.5))
    for k, (i, j) in enumerate([(0, 2), (0, 1)]):
        ax[k].scatter([q[i] for q in pts], [q[j] for q in pts], s=0.2, c="k", alpha=0.3)
        ax[k].set_xlabel("xyz"[i] + " [m] (map = first eDVS frame: x right, y down, z forward)")
        ax[k].set_ylabel("xyz"[j] + " [m]")
        ax[k].axis("equal")
    ax[1].invert_yaxis()
    fig.suptitle("freiburg1_desk, default, seed 1: occurrence-map voxels with O > 1 (top view, front view)")
    fig.tight_layout()
    fig.savefig(os.path.join(fig_dir, "map_freiburg1_desk.png"), dpi=80)
    plt.close(fig)
    return {"map": "![map](ebslam3d/map_freiburg1_desk.png)"}


def sweep_block(a, results, sweeps, sweep_path, fig_dir):
    """One table per swept parameter (mean RMSE, real-time factor, runs) and their plot."""
    sweep_runs = [r for r in results if r["kind"] == "sweep"]
    seeds = sorted(set(r["seed"] for r in sweep_runs))
    lines = []
    w = lines.append
    w(f"On {sweep_path}, first {a.sweep_duration:g} s, seeds {', '.join(map(str, seeds)) if seeds else 'none'}.")
    w("")
    names = list(sweeps)
    fig, axes = plt.subplots(len(names), 2, figsize=(9, 2.4 * len(names)))
    for row_i, name in enumerate(names):
        rs = [r for r in sweep_runs if r["sweep"] == name]
        vals = sorted(set(r["value"] for r in rs))
        if not vals:
            w(f"- {name}: not run.")
            w("")
            continue
        rm = [100 * mean([r["rmse_m"] for r in rs if r["value"] == v]) for v in vals]
        rt = [mean([r["realtime_factor"] for r in rs if r["value"] == v]) for v in vals]
        n = [len([r for r in rs if r["value"] == v]) for v in vals]
        axes[row_i][0].plot(vals, rm, "o-")
        axes[row_i][0].set_ylabel("RMSE [cm]")
        axes[row_i][0].set_xlabel(name)
        axes[row_i][1].plot(vals, rt, "o-")
        axes[row_i][1].set_ylabel("x real time")
        axes[row_i][1].set_xlabel(name)
        for ax in axes[row_i]:
            if name != "event share":
                ax.set_xscale("log")
        best = vals[min(range(len(vals)), key=lambda i: rm[i])]
        lines += pagegen.table([name] + [f"{v:g}" for v in vals],
                               [["RMSE [cm]"] + [f"{x:.2f}" for x in rm],
                                ["x real time"] + [f"{x:.1f}" for x in rt],
                                ["runs"] + [str(x) for x in n]])
        w("")
        w(f"Best on the tuning half: {best:g}.")
        w("")
    fig.tight_layout()
    fig.savefig(os.path.join(fig_dir, "sweeps.png"), dpi=70)
    plt.close(fig)
    w("![sweeps](ebslam3d/sweeps.png)")
    return {"sweeps": lines}


def bench_block(bench_path):
    """Medians of ebslam_ebslam3d_bench ({} without it)."""
    if not bench_path or not os.path.exists(bench_path):
        return {}
    rows = []
    for bm in json.load(open(bench_path))["benchmarks"]:
        if bm.get("run_type") == "aggregate" and bm.get("aggregate_name") != "median":
            continue
        rows.append(["%s" % bm["name"], "%.0fk" % (bm["events_per_s"] / 1e3),
                     "%.1fk" % (bm["stream_events_per_s"] / 1e3), "%.1f" % bm["realtime_factor"],
                     "%g" % bm["thesis_realtime_factor"] if bm["thesis_realtime_factor"] else "-",
                     "%.1f" % bm["peak_map_mib"]])
    return {"bench": pagegen.table(["benchmark", "events/s", "stream events/s", "x real time",
                                    "thesis x real time", "peak map [MiB]"], rows)}


def write_page(a, results, sweeps, sweep_path):
    """Rewrites the generated blocks of OUT/ebslam3d.md (the prose there describes the D-eDVS source)."""
    fig_dir = os.path.join(a.out, "ebslam3d")
    os.makedirs(fig_dir, exist_ok=True)
    main_runs = [r for r in results if r["kind"] == "main"]
    blocks = {"reproduce": f"`{a.command}`",
              "runs": f"Every hand-held TUM path ({', '.join(p for p in PATHS if any(r['path'] == p for r in main_runs))}), "
                      f"the first {a.duration:g} s of each, seeds 1..{a.seeds}.",
              "not-run": ("**Not run.** " + a.cut) if a.cut else ""}
    blocks.update(table_8_1_blocks(a, main_runs))
    tuned = [r for r in results if r["kind"] == "tuned"]
    d_all = [r for r in main_runs if r["preset"] == "default"]
    if tuned:
        blocks.update(tuned_block(tuned, d_all))
    if d_all and any(r["preset"] == "fast" for r in main_runs):
        blocks.update(summary_block(main_runs))
    blocks.update(path_plots(main_runs, fig_dir))
    blocks.update(map_plot(main_runs, fig_dir))
    blocks.update(sweep_block(a, results, sweeps, sweep_path, fig_dir))
    blocks.update(bench_block(a.bench))
    pagegen.update_page(os.path.join(a.out, "ebslam3d.md"), blocks)


if __name__ == "__main__":
    main()
