#!/usr/bin/env python3
"""Rewrites the coverage blocks of docs/results/exploration.md from the runs of
scripts/results/coverage_experiment.sh: the coverage planner against the gain planner and the
random baseline per layout (issue 55's bars), the held-out layouts apart, one line per run and
the coverage curves.

    scripts/results/coverage_report.py RUNS_DIR --plans src/ebslam/floor_plans \
        --held-out src/ebslam/floor_plans/held_out [--out docs/results]
"""
import argparse
import os
import sys

import matplotlib

matplotlib.use("Agg")
import matplotlib.pyplot as plt  # noqa: E402
import numpy as np  # noqa: E402

sys.path.insert(0, os.path.dirname(os.path.abspath(__file__)))
import pagegen  # noqa: E402
from exploration_report import read_csv, read_plan, series, time_to  # noqa: E402

INF = float("inf")


def plan_names(folder):
    return [read_plan(os.path.join(folder, n))[0] for n in sorted(os.listdir(folder)) if n.endswith(".txt")]


def median_time(runs, limit):
    """Median time to 90 % [s], runs that did not reach it within `limit` counted as infinite."""
    times = [r["t90"] if r["t90"] is not None and r["t90"] <= limit else INF for r in runs]
    return float(np.median(times)) if times else INF


def fmt_s(value):
    return f"{value:.0f} s" if np.isfinite(value) else "-"


def speed_up(slow, fast, slow_limit):
    """slow / fast median; a censored slow median gives a lower bound."""
    if not np.isfinite(fast):
        return "-"
    if not np.isfinite(slow):
        return f"> {slow_limit / fast:.1f}x"
    return f"{slow / fast:.1f}x"


def layout_rows(runs, layouts, seeds, limit, baseline_limit):
    rows = []
    for layout in layouts:
        c = [runs[k] for k in ((layout, "coverage", s) for s in seeds) if k in runs]
        g = [runs[k] for k in ((layout, "gain", s) for s in seeds) if k in runs]
        b = [runs[k] for k in ((layout, "random", s) for s in seeds) if k in runs]
        if not c:
            continue
        reached = sum(1 for r in c if r["t90"] is not None and r["t90"] <= limit)
        cm, gm, bm = median_time(c, limit), median_time(g, limit), median_time(b, baseline_limit)
        # "done": said in every run that reached >= 95 %, never below 90 %.
        high = [r for r in c if r["final"] >= 0.95 or r["done"] is not None]
        done_ok = sum(1 for r in high if r["done"] is not None)
        done_low = [r for r in c if r["done"] is not None and r["covered_at_done"] < 0.9]
        done_cov = [r["covered_at_done"] for r in c if r["done"] is not None]
        rmse_c = np.mean([r["rmse"] for r in c]) * 100
        rmse_g = np.mean([r["rmse"] for r in g]) * 100 if g else float("nan")
        rows.append([
            layout, f"{reached}/{len(c)}", fmt_s(cm), fmt_s(gm), fmt_s(bm),
            speed_up(gm, cm, limit), speed_up(bm, cm, baseline_limit),
            f"{done_ok} of {len(high)}" + (f" (min {100 * min(done_cov):.1f} %)" if done_cov else ""),
            f"{len(done_low)}",
            f"{sum(r['diverged'] for r in c)} / {sum(r['diverged'] for r in g)}",
            f"{rmse_c:.2f} / {rmse_g:.2f} cm ({rmse_c / rmse_g:.2f}x)" if g else f"{rmse_c:.2f} cm",
            f"{np.median([r['wall'] for r in c]):.0f} / {np.median([r['wall'] for r in g]):.0f} s" if g else "-",
        ])
    header = ["layout", "coverage: 90 % within 600 s", "coverage: median time to 90 %",
              "gain: median", "random: median", "speed-up over gain", "speed-up over random",
              "done said (runs >= 95 % or done)", "done below 90 %", "diverged (coverage / gain)",
              "RMSE aligned, mean (coverage / gain)", "wall time per run, median (coverage / gain)"]
    return pagegen.table(header, rows)


def run_rows(runs, layouts, seeds):
    rows = []
    for layout in layouts:
        for method in ("coverage", "gain", "random"):
            for s in seeds:
                r = runs.get((layout, method, s))
                if r is None:
                    continue
                slam = method != "random"

                def at(t):
                    i = min(np.searchsorted(r["t"], t), len(r["cov"]) - 1)
                    ended = r["t"][-1] < t - 1  # a coverage run ends once it is back after "done"
                    return f"{100 * r['cov'][i]:.1f} %" + (f" (ended at {r['t'][-1]:.0f} s)" if ended else "")

                rows.append([
                    layout, method, s, at(300), at(600), fmt_s(r["t90"] if r["t90"] is not None else INF),
                    (f"{r['done']:.0f} s ({100 * r['covered_at_done']:.1f} %)" if r["done"] is not None else "-"),
                    f"{r['bumps_per_min']:.1f}",
                    f"{100 * r['rmse']:.2f} cm" if slam else "-",
                    f"{100 * r['rmse_raw']:.2f} cm" if slam else "-",
                    f"{r['wall']:.0f} s",
                ])
    header = ["layout", "planner", "seed", "covered at 5 min", "covered at 10 min", "time to 90 %",
              "done at (true coverage)", "bumps / min", "RMSE aligned", "RMSE raw", "wall time"]
    return pagegen.table(header, rows)


def plot_curves(runs, layouts, seeds, path):
    n = len(layouts)
    cols = min(4, n)
    rows = (n + cols - 1) // cols
    fig, axes = plt.subplots(rows, cols, figsize=(4 * cols, 3 * rows), squeeze=False)
    colours = {"coverage": "tab:red", "gain": "tab:green", "random": "tab:blue"}
    for ax, layout in zip(axes.flat, layouts):
        for method, colour in colours.items():
            for s in seeds:
                r = runs.get((layout, method, s))
                if r is None:
                    continue
                keep = r["t"] <= 600.0
                ax.plot(r["t"][keep] / 60.0, 100 * r["cov"][keep], color=colour, lw=1, alpha=0.7,
                        label=method if s == seeds[0] else None)
        ax.axhline(90, color="k", lw=0.5, ls=":")
        ax.set_title(layout)
        ax.set_xlabel("simulated minutes")
        ax.set_ylabel("covered [%]")
        ax.set_ylim(0, 100)
        ax.set_xlim(0, 10)
    for ax in list(axes.flat)[n:]:
        ax.axis("off")
    axes.flat[0].legend(loc="lower right", fontsize=8)
    fig.tight_layout()
    fig.savefig(path, dpi=80)
    plt.close(fig)


def main():
    parser = argparse.ArgumentParser()
    parser.add_argument("runs")
    parser.add_argument("--plans", required=True)
    parser.add_argument("--held-out", required=True)
    parser.add_argument("--out", default="docs/results")
    parser.add_argument("--command", default="scripts/results/coverage_experiment.sh")
    parser.add_argument("--limit", type=float, default=600.0, help="a planner run's length [s]")
    parser.add_argument("--baseline-limit", type=float, default=2400.0)
    args = parser.parse_args()

    runs = {}
    for row in read_csv(os.path.join(args.runs, "summary.csv")):
        stem = os.path.join(args.runs, f"{row['layout']}_{row['method']}_s{row['seed']}")
        t, cov, _ = series(stem + "_series.csv")
        t90 = time_to(t, cov, 0.9)
        done = float(row["done_s"])
        runs[(row["layout"], row["method"], int(row["seed"]))] = dict(
            t=t, cov=cov, t90=t90, final=float(row["final_covered"]),
            done=done if done >= 0 else None, covered_at_done=float(row["covered_at_done"]),
            rmse=float(row["rmse_aligned_m"]), rmse_raw=float(row["rmse_raw_m"]),
            diverged=int(row["diverged"]), bumps_per_min=float(row["bumps_per_min"]),
            wall=float(row["wall_s"]))
    seeds = sorted({k[2] for k in runs})
    shipped = [l for l in plan_names(args.plans) if any(k[0] == l for k in runs)]
    held_out = [l for l in plan_names(args.held_out) if any(k[0] == l for k in runs)]
    fig_dir = os.path.join(args.out, "exploration")
    os.makedirs(fig_dir, exist_ok=True)
    plot_curves(runs, shipped + held_out, seeds, os.path.join(fig_dir, "coverage_planners.png"))
    blocks = {
        "coverage-reproduce": f"`{args.command}` (seeds {', '.join(str(s) for s in seeds)})",
        "coverage-layouts": layout_rows(runs, shipped, seeds, args.limit, args.baseline_limit),
        "coverage-held-out": layout_rows(runs, held_out, seeds, args.limit, args.baseline_limit),
        "coverage-runs": run_rows(runs, shipped + held_out, seeds),
        "coverage-curves": "![coverage planners](exploration/coverage_planners.png)",
    }
    pagegen.update_page(os.path.join(args.out, "exploration.md"), blocks)


if __name__ == "__main__":
    main()
