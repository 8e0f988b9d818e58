#!/usr/bin/python3
"""Rewrites the generated blocks of docs/results/exploration.md (tables, coverage curves, pictures
like thesis fig. 7.9 and 7.10) from the output folder of ebslam_explore; the prose is hand-written.

    scripts/results/exploration_report.py RUNS_DIR --plans src/ebslam/floor_plans [--bench bench.json]
        [--out docs/results] [--command "scripts/results/exploration_experiment.sh"]
"""
import argparse
import csv
import json
import os
import sys

import matplotlib

matplotlib.use("Agg")
import matplotlib.pyplot as plt  # noqa: E402
import numpy as np  # noqa: E402
from matplotlib.path import Path  # noqa: E402

sys.path.insert(0, os.path.dirname(os.path.abspath(__file__)))
import pagegen  # noqa: E402

def read_plan(path):
    """Returns (name, walls, obstacles) of a floor-plan file (format: src/ebslam/include/ebslam/simulation/floor_plan.h)."""
    name, polygons, current = os.path.splitext(os.path.basename(path))[0], [], None
    for raw in open(path):
        fields = raw.split("#")[0].split()
        if not fields:
            continue
        if fields[0] in ("walls", "obstacle"):
            current = (fields[0], [])
            polygons.append(current)
        elif fields[0] == "name":
            name = fields[1]
        elif fields[0] == "start":
            pass
        else:
            current[1].append((float(fields[0]), float(fields[1])))
    walls = [np.array(p) for k, p in polygons if k == "walls"]
    obstacles = [np.array(p) for k, p in polygons if k == "obstacle"]
    return name, walls[0], obstacles


def draw_room(ax, plan):
    _, walls, obstacles = plan
    for polygon in [walls] + obstacles:
        ax.plot(polygon[:, 0], polygon[:, 1], "k-", lw=1.5)


def read_csv(path):
    with open(path) as f:
        return list(csv.DictReader(f))


def series(path):
    rows = read_csv(path)
    return (np.array([float(r["t_s"]) for r in rows]), np.array([float(r["covered"]) for r in rows]),
            np.array([float(r["position_error_m"]) for r in rows]))


def time_to(t, covered, level):
    hit = np.nonzero(covered >= level)[0]
    return t[hit[0]] if hit.size else None


def fmt_time(value):
    return "-" if value is None else f"{value:.0f} s"


def layouts_block(args, runs, layouts, seeds):
    """Per layout: the gain planner against the baseline on the seeds the planner ran."""
    result = {}
    # Per layout.
    lines = ["| layout | gain: 90 % reached (runs) | gain: time to 90 % (median) | random: time to 90 % (median) | speed-up | RMSE aligned (max over seeds) | diverged |",
             "|---|---|---|---|---|---|---|"]
    for layout in layouts:
        g = [runs[(layout, "gain", s)] for s in seeds if (layout, "gain", s) in runs]
        # The baseline on the seeds the planner ran (the same rooms, ceilings and sensors).
        b = [runs[(layout, "random", s)] for s in seeds
             if (layout, "random", s) in runs and (layout, "gain", s) in runs]
        g90 = [time_to(r["t"], r["cov"], 0.9) for r in g]
        b90 = [time_to(r["t"], r["cov"], 0.9) for r in b]
        within = sum(1 for v in g90 if v is not None and v <= args.limit)
        inf = float("inf")
        gm = np.median([v if v is not None else inf for v in g90]) if g90 else inf
        bm = np.median([v if v is not None else inf for v in b90]) if b90 else inf
        ratio = bm / gm if np.isfinite(gm) and gm > 0 else float("nan")
        rmse = max(float(r["row"]["rmse_aligned_m"]) for r in g) * 100 if g else float("nan")
        div = sum(int(r["row"]["diverged"]) for r in g)
        ratio_text = f"{ratio:.2f}x" if np.isfinite(ratio) else ("-" if not np.isfinite(gm) else "> run length")
        lines.append(f"| {layout} | {within}/{len(g)} within {args.limit:.0f} s | "
                     f"{fmt_time(gm if np.isfinite(gm) else None)} | "
                     f"{fmt_time(bm if np.isfinite(bm) else None)} | {ratio_text} | {rmse:.2f} cm | {div}/{len(g)} |")
    result["layouts"] = lines
    return result


def runs_block(args, runs, layouts, seeds):
    """One line per run."""
    result = {}
    # Per run.
    lines = ["| layout | method | seed | reachable area | covered at 5 min | covered at 10 min | time to 90 % | bumps / min | RMSE aligned | RMSE raw | max raw error | collapses detected | planner CPU / call |",
              "|---|---|---|---|---|---|---|---|---|---|---|---|---|"]
    for layout in layouts:
        for method in ("gain", "random"):
            for s in seeds:
                r = runs.get((layout, method, s))
                if r is None:
                    continue
                row = r["row"]

                def at(tq):
                    k = np.searchsorted(r["t"], tq)
                    if r["t"][-1] >= tq - 1:
                        return f"{r['cov'][min(k, len(r['cov']) - 1)] * 100:.1f} %"
                    # A run stopped once 90 % were covered (ebslam_explore --stop-at 0.9).
                    return ">= 90 % (stopped)" if r["cov"][-1] >= 0.9 else "-"
                t10 = r["t"] <= args.limit
                bumps = float(row["bumps_per_min"])
                slam = method == "gain"
                lines.append(
                    f"| {layout} | {method} | {s} | {float(row['reachable_area_m2']):.1f} m^2 | {at(300)} | "
                    f"{at(args.limit)} | {fmt_time(time_to(r['t'], r['cov'], 0.9))} | {bumps:.1f} | "
                    + (f"{float(row['rmse_aligned_m']) * 100:.2f} cm | {float(row['rmse_raw_m']) * 100:.2f} cm | "
                       f"{float(row['max_error_m']) * 100:.1f} cm | {row.get('collapses', '-')} | "
                       f"{float(row['planner_ms_per_call']):.3f} ms |"
                       if slam else "- | - | - | - | - |"))
                del t10
    result["runs"] = lines
    return result


def leaving_block(runs, layouts, seeds, plans):
    """The gain runs whose last planned path leaves the room."""
    result = {}
    # Where the planner wanted to go at the end: a last plan that leaves the room went through a
    # gap in the blocked cells along the walls (the cells beyond the walls stay unexplored, so
    # their gain stays high).
    leaving = []
    for layout in layouts:
        walls = Path(plans[layout][1])
        for s in seeds:
            r = runs.get((layout, "gain", s))
            if r is None or not os.path.exists(r["stem"] + "_path.csv"):
                continue
            path = read_csv(r["stem"] + "_path.csv")
            if any(not walls.contains_point((float(q["x"]), float(q["y"]))) for q in path):
                leaving.append(f"{layout} seed {s}")
    gain_runs = sum(1 for k in runs if k[1] == "gain")
    result["leaving"] = (f"Last planned path leaving the room (through a gap in the blocked cells along the walls): "
                         f"{len(leaving)} of {gain_runs} gain runs" + (f" ({', '.join(leaving)})." if leaving else "."))
    return result


def plot_curves(args, runs, layouts, seeds, fig_dir):
    """Coverage and EB-SLAM's raw position error over time."""
    result = {}
    # Coverage curves.
    fig, axes = plt.subplots(1, len(layouts), figsize=(5 * len(layouts), 3.8), squeeze=False)
    for ax, layout in zip(axes[0], layouts):
        for method, colour in (("gain", "tab:red"), ("random", "tab:blue")):
            for s in seeds:
                r = runs.get((layout, method, s))
                if r is None:
                    continue
                ax.plot(r["t"] / 60, r["cov"] * 100, color=colour, lw=1, alpha=0.7,
                        label=("gain planner (EB-SLAM)" if method == "gain" else "random bump-and-turn") if s == seeds[0] else None)
        ax.axhline(90, color="k", ls=":", lw=0.8)
        ax.axvline(args.limit / 60, color="k", ls=":", lw=0.8)
        ax.set_title(layout)
        ax.set_xlabel("simulated time [min]")
        ax.set_ylabel("covered reachable free area [%]")
        ax.set_ylim(0, 100)
        ax.legend(loc="lower right", fontsize=8)
    fig.tight_layout()
    fig.savefig(os.path.join(fig_dir, "coverage.png"), dpi=90)
    plt.close(fig)

    # Localisation error over time.
    fig, axes = plt.subplots(1, len(layouts), figsize=(5 * len(layouts), 3.2), squeeze=False)
    for ax, layout in zip(axes[0], layouts):
        for s in seeds:
            r = runs.get((layout, "gain", s))
            if r is not None:
                ax.plot(r["t"] / 60, r["err"] * 100, lw=1, label=f"seed {s}")
        ax.set_title(f"{layout}: EB-SLAM position error (raw)")
        ax.set_xlabel("simulated time [min]")
        ax.set_ylabel("error [cm]")
        ax.legend(fontsize=7)
    fig.tight_layout()
    fig.savefig(os.path.join(fig_dir, "slam_error.png"), dpi=90)
    plt.close(fig)

    result["coverage"] = "![coverage](exploration/coverage.png)"
    result["error"] = "![error](exploration/slam_error.png)"
    return result


def draw_covered(ax, r, plan):
    """The covered area (ebslam_explore's covered.png: 2 cm raster from the room's lower-left
    corner, row r at y = y_min + r * 2 cm) in light red."""
    name = r["stem"] + "_covered.png"
    if not os.path.exists(name):
        return
    covered = plt.imread(name)
    if covered.ndim == 3:
        covered = covered[..., 0]
    _, walls, _ = plan
    x0, y0 = walls.min(axis=0)
    res = 0.02
    rgba = np.zeros(covered.shape + (4,))
    rgba[..., 0] = 1.0
    rgba[..., 1] = 0.75
    rgba[..., 2] = 0.75
    rgba[..., 3] = (covered > 0.5) * 0.6
    ax.imshow(rgba, origin="lower", extent=[x0, x0 + covered.shape[1] * res, y0, y0 + covered.shape[0] * res],
              interpolation="nearest", zorder=0)


def plot_paths(runs, layouts, seeds, plans, fig_dir):
    """Covered area, paths, bumps and blocked cells per layout (first seed)."""
    result = {}
    # Pictures like fig. 7.10 (one per layout, first seed) and fig. 7.9 (maps of the first layout).
    lines = []
    for layout in layouts:
        # The first seed with a gain run on this layout.
        s = next((x for x in seeds if (layout, "gain", x) in runs), seeds[0])
        fig, axes = plt.subplots(1, 2, figsize=(11, 4.8))
        for ax, method in zip(axes, ("gain", "random")):
            r = runs.get((layout, method, s))
            if r is None:
                continue
            draw_covered(ax, r, plans[layout])
            gt = np.loadtxt(r["stem"] + "_gt.tum")
            ax.plot(gt[:, 1], gt[:, 2], "r-", lw=0.6)
            if method == "gain":
                est = np.loadtxt(r["stem"] + "_est.tum")
                ax.plot(est[:, 1], est[:, 2], "g-", lw=0.4)
                hexes = read_csv(r["stem"] + "_hex.csv")
                blocked = np.array([(float(h["x"]), float(h["y"])) for h in hexes if h["blocked"] == "1"])
                if blocked.size:
                    ax.plot(blocked[:, 0], blocked[:, 1], "o", color="tab:blue", ms=2.5)
                bumps = read_csv(r["stem"] + "_bumps.csv")
                if bumps:
                    b = np.array([(float(p["x"]), float(p["y"])) for p in bumps])
                    ax.plot(b[:, 0], b[:, 1], "o", color="orange", ms=2.5)
            draw_room(ax, plans[layout])
            final = r["cov"][-1] * 100
            ax.set_title(f"{layout}, {method}, seed {s}: {final:.0f} % covered in {r['t'][-1] / 60:.0f} min")
            ax.set_aspect("equal")
        fig.tight_layout()
        name = f"{layout}_paths.png"
        fig.savefig(os.path.join(fig_dir, name), dpi=80)
        plt.close(fig)
        lines += [f"![{layout}](exploration/{name})", ""]
    result["paths"] = lines
    return result


def plot_maps(runs, layouts, seeds, plans, fig_dir):
    """Z, E and the gain at the end of the first layout's first gain run."""
    result = {}
    layout = layouts[0]
    seed = next((x for x in seeds if (layout, "gain", x) in runs), seeds[0])
    r = runs.get((layout, "gain", seed))
    if r is not None:
        hexes = read_csv(r["stem"] + "_hex.csv")
        xy = np.array([(float(h["x"]), float(h["y"])) for h in hexes])
        _, walls, _ = plans[layout]
        lo, hi = walls.min(axis=0) - 1.0, walls.max(axis=0) + 1.0
        keep = np.all((xy >= lo) & (xy <= hi), axis=1)
        gt = np.loadtxt(r["stem"] + "_gt.tum")
        path = read_csv(r["stem"] + "_path.csv")
        fig, axes = plt.subplots(1, 3, figsize=(16, 5))
        for ax, key, title in zip(axes, ("z", "e", "gain"), ("localisation exploration map Z", "obstacle exploration map E", "information gain G")):
            values = np.array([float(h[key]) for h in hexes])[keep]
            ax.scatter(xy[keep, 0], xy[keep, 1], c=values, cmap="Greys", s=9, marker="h")
            blocked = np.array([h["blocked"] == "1" for h in hexes])[keep]
            if key == "e":
                ax.plot(xy[keep][blocked, 0], xy[keep][blocked, 1], "o", color="tab:blue", ms=2.5)
                bumps = read_csv(r["stem"] + "_bumps.csv")
                if bumps:
                    b = np.array([(float(p["x"]), float(p["y"])) for p in bumps])
                    ax.plot(b[:, 0], b[:, 1], "o", color="orange", ms=2.5)
            ax.plot(gt[:, 1], gt[:, 2], "r-", lw=0.5)
            if path:
                p = np.array([(float(q["x"]), float(q["y"])) for q in path])
                ax.plot(p[:, 0], p[:, 1], "m-", lw=2)
            draw_room(ax, plans[layout])
            ax.set_title(title + " (darker = higher)")
            ax.set_aspect("equal")
        fig.tight_layout()
        fig.savefig(os.path.join(fig_dir, "maps.png"), dpi=80)
        plt.close(fig)
        result["maps"] = [f"{layout}, seed {seed}: true path (red), last planned path (magenta); blocked cells blue and bumps orange in E.", "",
                          "![maps](exploration/maps.png)"]
    return result


def bench_block(bench_path):
    """ebslam_exploration_bench's figures ({} without it)."""
    result = {}
    if bench_path:
        bench = json.load(open(bench_path))
        rows = {b["name"]: b for b in bench["benchmarks"] if b.get("run_type") == "iteration" or "aggregate_name" not in b}
        lines = ["| benchmark | CPU time | notes |", "|---|---|---|"]
        for name, b in rows.items():
            cpu = b["cpu_time"]
            unit = b.get("time_unit", "ns")
            note = ""
            if name.startswith("BM_SlamControlPeriod"):
                note = f"per 50 ms period: {cpu / 40:.3f} {unit} ({b.get('events_per_period', 0):.0f} events)"
            if name.startswith("BM_PlannerStep"):
                note = f"{b.get('expanded_nodes', 0):.0f} nodes expanded of {b.get('grid_cells', 0):.0f} cells"
            if name.startswith("BM_SimulatorControlPeriod"):
                note = f"{b.get('realtime_factor', 0):.1f}x real time"
            lines.append(f"| {name} | {cpu:.3f} {unit} | {note} |")
        result["bench"] = lines
    return result


def main():
    parser = argparse.ArgumentParser()
    parser.add_argument("runs")
    parser.add_argument("--plans", required=True)
    parser.add_argument("--bench")
    parser.add_argument("--out", default="docs/results")
    parser.add_argument("--command", default="scripts/results/exploration_experiment.sh")
    parser.add_argument("--note", default="", help="a paragraph added after the setup")
    parser.add_argument("--limit", type=float, default=600.0, help="time limit of a gain run [s]")
    args = parser.parse_args()

    summary = read_csv(os.path.join(args.runs, "summary.csv"))
    plans = {}
    for name in sorted(os.listdir(args.plans)):
        if name.endswith(".txt"):
            plan = read_plan(os.path.join(args.plans, name))
            plans[plan[0]] = plan
    layouts = [l for l in plans if any(r["layout"] == l for r in summary)]
    seeds = sorted({int(r["seed"]) for r in summary})
    fig_dir = os.path.join(args.out, "exploration")
    os.makedirs(fig_dir, exist_ok=True)

    runs = {}
    for r in summary:
        stem = os.path.join(args.runs, f"{r['layout']}_{r['method']}_s{r['seed']}")
        t, cov, err = series(stem + "_series.csv")
        runs[(r["layout"], r["method"], int(r["seed"]))] = dict(row=r, stem=stem, t=t, cov=cov, err=err)

    blocks = {
        "reproduce": f"`{args.command}`",
        "seeds": f"Seeds: gain planner {', '.join(str(x) for x in sorted({k[2] for k in runs if k[1] == 'gain'}))}, "
                 f"baseline {', '.join(str(x) for x in sorted({k[2] for k in runs if k[1] == 'random'}))}.",
        "note": args.note,
    }

    blocks.update(layouts_block(args, runs, layouts, seeds))
    blocks.update(runs_block(args, runs, layouts, seeds))
    blocks.update(leaving_block(runs, layouts, seeds, plans))
    blocks.update(plot_curves(args, runs, layouts, seeds, fig_dir))
    blocks.update(plot_paths(runs, layouts, seeds, plans, fig_dir))
    blocks.update(plot_maps(runs, layouts, seeds, plans, fig_dir))
    blocks.update(bench_block(args.bench))
    pagegen.update_page(os.path.join(args.out, "exploration.md"), blocks)


if __name__ == "__main__":
    main()
