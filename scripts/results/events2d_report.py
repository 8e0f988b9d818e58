#!/usr/bin/python3
"""Rewrites the generated blocks of docs/results/events2d.md (tables, trajectory plots, maps next
to the ceiling) from the output folder of ebslam_experiment_events2d and, optionally, the JSON of
ebslam_ebpf_bench. The page's prose is hand-written.

    scripts/results/events2d_report.py RUNS_DIR [--bench bench.json] [--out docs/results]

RUNS_DIR holds runs.csv and, from the noise runs, noise_runs.csv and denoise.csv (also in its
subfolders); docs/results/events2d/ keeps a copy of all three, so the tables can be regenerated
from it: `scripts/results/events2d_report.py docs/results/events2d`.
"""
import argparse
import csv
import glob
import json
import os
import shutil
import sys

import matplotlib

matplotlib.use("Agg")
import matplotlib.pyplot as plt  # noqa: E402
import numpy as np  # noqa: E402

sys.path.insert(0, os.path.dirname(os.path.abspath(__file__)))
import pagegen  # noqa: E402

THESIS_EBPF = {(1, 50): 34400, (1, 100): 18100, (1, 250): 7500,
               (3, 50): 74800, (3, 100): 40400, (3, 250): 17200}
THESIS_SLAM = {5: (35.4, 51.2, "18/40", 87800), 10: (5.9, 5.5, "5/40", 80700),
               25: (6.0, 5.5, "4/40", 65600), 75: (6.0, 5.4, "3/40", 38800)}


def load_tum(path):
    return np.loadtxt(path, comments="#")


def yaw(q):
    x, y, z, w = q[:, 0], q[:, 1], q[:, 2], q[:, 3]
    return np.arctan2(2 * (w * z + x * y), 1 - 2 * (y * y + z * z))


def align2d(est_xy, gt_xy):
    """Least-squares rigid 2D alignment (Kabsch) of est onto gt."""
    me, mg = est_xy.mean(0), gt_xy.mean(0)
    h = (est_xy - me).T @ (gt_xy - mg)
    u, _, vt = np.linalg.svd(h)
    d = np.sign(np.linalg.det(vt.T @ u.T))
    r = vt.T @ np.diag([1, d]) @ u.T
    return (r @ (est_xy - me).T).T + mg


def plot_run(runs_dir, traj, stem, title, out_png, align):
    gt = load_tum(os.path.join(runs_dir, traj, "ground_truth.tum"))
    est = load_tum(os.path.join(runs_dir, traj, stem + ".tum"))
    gx = np.interp(est[:, 0], gt[:, 0], gt[:, 1])
    gy = np.interp(est[:, 0], gt[:, 0], gt[:, 2])
    exy = est[:, 1:3]
    if align:
        exy = align2d(exy, np.c_[gx, gy])
    err = np.hypot(exy[:, 0] - gx, exy[:, 1] - gy)
    gth = np.interp(est[:, 0], gt[:, 0], np.unwrap(yaw(gt[:, 4:8])))
    eth = np.unwrap(yaw(est[:, 4:8]))
    dth = np.degrees(np.angle(np.exp(1j * (eth - gth))))
    if align:
        dth -= np.mean(dth)
    fig, ax = plt.subplots(1, 2, figsize=(11, 4.2))
    ax[0].plot(gt[:, 1], gt[:, 2], "b-", lw=1, label="ground truth")
    ax[0].plot(exy[:, 0], exy[:, 1], "r-", lw=0.6, label="estimate" + (" (aligned)" if align else ""))
    ax[0].plot(gt[0, 1], gt[0, 2], "kx", ms=8)
    ax[0].set_aspect("equal")
    ax[0].set_xlabel("x [m]")
    ax[0].set_ylabel("y [m]")
    ax[0].legend(fontsize=8)
    ax[0].set_title(title, fontsize=9)
    ax[1].plot(est[:, 0], err * 100, "r-", lw=0.6, label="position [cm]")
    ax[1].plot(est[:, 0], np.abs(dth), "g-", lw=0.6, label="|rotation| [deg]")
    ax[1].set_xlabel("time [s]")
    ax[1].legend(fontsize=8)
    ax[1].set_title("error over time", fontsize=9)
    fig.tight_layout()
    fig.savefig(out_png, dpi=80)
    plt.close(fig)


DEFAULT_FILTER = ("100000", "3", "1")  # window_us, min_support, polarity_match (event_denoiser.h)
TUNING_TRAJECTORY = "freiburg2_pioneer_360"


def read_csvs(paths):
    rows = []
    for path in paths:
        rows += list(csv.DictReader(open(path)))
    return rows


def rms(values):
    return float(np.sqrt(np.mean(np.square(values)))) if values else float("nan")


def cm(value):
    return "-" if np.isnan(value) else f"{value:.2f} cm"


def median_benchmarks(bench):
    """(name, entry) of a Google Benchmark JSON: with repetitions, only the median of each."""
    for b in bench["benchmarks"]:
        if b.get("run_type") == "aggregate" and b.get("aggregate_name") != "median":
            continue
        if b.get("run_type") == "iteration" and b.get("repetitions", 1) > 1:
            continue
        yield b.get("run_name", b["name"]), b


def filter_blocks(den_rows):
    """Blocks of the filter's quality against the simulator's labels."""
    rows = []
    for r in sorted(den_rows, key=lambda r: (r["trajectory"], float(r["noise_rate"]))):
        if (r["window_us"], r["min_support"], r["polarity_match"]) != DEFAULT_FILTER:
            continue
        if r.get("refractory", "0") != "0":
            continue
        sig, kept = int(r["signal"]), int(r["signal_kept"])
        noi, rem = int(r["noise"]), int(r["noise_removed"])
        rows.append([r["trajectory"], f"{float(r['noise_rate']):g}", f"{sig:,}",
                     f"{100.0 * kept / sig:.1f} %", f"{noi:,}", f"{100.0 * rem / noi:.1f} %"])
    blocks = {"noise-filter": pagegen.table(
        ["trajectory", "noise [Hz/pixel]", "signal events", "signal kept", "noise events",
         "noise removed"], rows)}
    trajs = sorted({r["trajectory"] for r in den_rows})
    keys = sorted({(int(r["window_us"]), int(r["min_support"]), int(r["polarity_match"]))
                   for r in den_rows if float(r["noise_rate"]) == 1.0})
    rows = []
    for w, k, pol in keys:
        cells = []
        for t in trajs:
            hit = [r for r in den_rows if r["trajectory"] == t and float(r["noise_rate"]) == 1.0
                   and int(r["window_us"]) == w and int(r["min_support"]) == k
                   and int(r["polarity_match"]) == pol]
            if hit:
                r = hit[0]
                cells.append(f"{100.0 * int(r['signal_kept']) / int(r['signal']):.1f} / "
                             f"{100.0 * int(r['noise_removed']) / int(r['noise']):.1f} %")
            else:
                cells.append("")
        rows.append([f"{w / 1000:g} ms", k, "yes" if pol else "no"] + cells)
    blocks["noise-filter-choice"] = pagegen.table(["window", "support", "polarity"] + trajs, rows)
    reported = [r for r in den_rows if r["trajectory"] != TUNING_TRAJECTORY
                and float(r["noise_rate"]) == 1.0
                and (r["window_us"], r["min_support"], r["polarity_match"]) == DEFAULT_FILTER]
    if reported:
        r = reported[0]
        kept = 100.0 * int(r["signal_kept"]) / int(r["signal"])
        removed = 100.0 * int(r["noise_removed"]) / int(r["noise"])
        blocks["noise-filter-reported"] = (
            f"On {r['trajectory']} at 1 Hz the default filter keeps {kept:.1f} % of the signal "
            f"and removes {removed:.1f} % of the noise.")
    return blocks


def accuracy_blocks(noise_rows, base_rows):
    """Blocks of the localisation accuracy against the noise rate; base_rows: runs.csv rows of
    the default noise (0.1 Hz), the 'off' rows at 0.1 Hz."""
    rates = sorted({float(r["noise_rate"]) for r in noise_rows})
    rows = list(noise_rows)
    for r in base_rows:
        if (r["method"] == "ebpf" and r["resample"] == "25") or (
                r["method"] == "ebslam2d" and r["particles"] == "10"):
            rows.append(dict(r, noise_rate="0.1", variant="off"))
    order = {"off": 0, "filter": 1, "robust": 2, "filter+robust": 3}
    combos = sorted({(r["trajectory"], float(r["noise_rate"]), r["variant"]) for r in rows},
                    key=lambda c: (c[0], c[1], order.get(c[2], 9)))
    lines = []
    for t, rate, v in combos:
        sel = [r for r in rows if r["trajectory"] == t and float(r["noise_rate"]) == rate
               and r["variant"] == v]
        pf = [r for r in sel if r["method"] == "ebpf"]
        sl = [r for r in sel if r["method"] == "ebslam2d"]
        pf_txt = ["-", "-", "-"] if not pf else [
            str(len(pf)), f"{100 * rms([float(r['rmse_pos_m']) for r in pf]):.2f} cm",
            f"{sum(r['failed'] == '1' for r in pf)}/{len(pf)}"]
        ok = [r for r in sl if r["failed"] == "0"]
        if not sl:
            sl_txt = ["-", "-", "-"]
        else:
            worst = max(float(r["rmse_pos_m"]) for r in sl) * 100
            rm = "-" if not ok else f"{100 * rms([float(r['rmse_pos_m']) for r in ok]):.2f} cm"
            sl_txt = [str(len(sl)), f"{rm} ({worst:.1f})", f"{len(sl) - len(ok)}/{len(sl)}"]
        half = " (tuning)" if t == TUNING_TRAJECTORY else ""
        lines.append([f"{t}{half}", f"{rate:g}", v] + pf_txt + sl_txt)
    return {
        "noise-seeds": "Runs per cell: the seeds the sweep completed (highest seed: " + ", ".join(
            f"{max(int(r['seed']) for r in noise_rows if float(r['noise_rate']) == x)} at "
            f"{x:g} Hz" for x in rates) + ").",
        "noise-accuracy": pagegen.table(
            ["trajectory", "noise [Hz/pixel]", "variant", "EB-PF runs", "EB-PF RMSE",
             "EB-PF diverged", "EB-SLAM-2D runs", "EB-SLAM-2D RMSE (worst)",
             "EB-SLAM-2D diverged"], lines)}


def filter_speed_block(bench_path):
    """The filter's cost per event beside EB-SLAM-2D's and EB-PF's ({} without the benchmark)."""
    if not bench_path or not os.path.exists(bench_path):
        return {}
    per_event = {}
    for name, b in median_benchmarks(json.load(open(bench_path))):
        eps = b.get("events_per_s", b.get("items_per_second", 0))
        if eps:
            per_event[name] = 1e9 / eps
    baf = [(n, v) for n, v in per_event.items() if n.startswith("BM_BackgroundActivityFilter")]
    slam = per_event.get("BM_Ebslam2d/B:3/N:10")
    pf = per_event.get("BM_Ebpf/B:3/N:50")
    if not baf:
        return {}
    rows = [[n, f"{v:.1f}", "" if not slam else f"{100 * v / slam:.1f} %"] for n, v in baf]
    if slam:
        rows.append(["BM_Ebslam2d/B:3/N:10", f"{slam:.1f}", "100 %"])
    if pf:
        rows.append(["BM_Ebpf/B:3/N:50", f"{pf:.1f}", ""])
    return {"noise-filter-speed": pagegen.table(
        ["benchmark", "ns per event", "share of EB-SLAM-2D N = 10"], rows)}


def noise_blocks(runs_dir, base_rows, bench_path, out_dir=None):
    """Blocks of the background-activity section from <runs_dir>[/*]/noise_runs.csv and
    denoise.csv (merged copies go to out_dir); {} without noise runs."""
    noise_rows = read_csvs(sorted(glob.glob(os.path.join(runs_dir, "noise_runs.csv")) +
                                  glob.glob(os.path.join(runs_dir, "*", "noise_runs.csv"))))
    den_rows = read_csvs(sorted(glob.glob(os.path.join(runs_dir, "denoise.csv")) +
                                glob.glob(os.path.join(runs_dir, "*", "denoise.csv"))))
    if not noise_rows:
        return {}
    for name, data in (("noise_runs.csv", noise_rows), ("denoise.csv", den_rows)):
        if data and out_dir and os.path.abspath(runs_dir) != os.path.abspath(out_dir):
            with open(os.path.join(out_dir, name), "w", newline="") as f:
                w = csv.DictWriter(f, fieldnames=list(data[0].keys()))
                w.writeheader()
                w.writerows(data)
    blocks = filter_blocks(den_rows)
    blocks.update(accuracy_blocks(noise_rows, base_rows))
    blocks.update(filter_speed_block(bench_path))
    return blocks


def ebpf_blocks(rows, trajs):
    """EB-PF: summary per K, per trajectory, G0 sweep."""
    ebpf = [r for r in rows if r["method"] == "ebpf"]
    if not ebpf:
        return {}
    lines = []
    for k in sorted({int(r["resample"]) for r in ebpf}):
        sel = [r for r in ebpf if int(r["resample"]) == k]
        ok = [r for r in sel if r["failed"] == "0"]
        pos = rms([float(r["rmse_pos_m"]) for r in sel]) * 100
        raw = rms([float(r["rmse_pos_raw_m"]) for r in sel]) * 100
        off = np.mean([float(r["best_offset_s"]) for r in sel]) * 1e3
        sm = rms([float(r["rmse_pos_smoothed_m"]) for r in sel]) * 100
        rot = rms([float(r["rmse_rot_deg"]) for r in sel])
        eps = np.mean([float(r["events_per_s"]) for r in sel])
        lines.append([k, len(sel), f"{pos:.2f} cm", f"{raw:.2f} cm", f"{off:+.0f} ms",
                      f"{sm:.2f} cm", f"{rot:.2f} deg", f"{len(sel) - len(ok)}/{len(sel)}",
                      f"{eps:,.0f}"])
    blocks = {"ebpf": pagegen.table(
        ["K", "runs", "position RMSE", "raw (no latency comp.)", "best offset of raw",
         "smoothed (mean filter)", "rotation RMSE", "diverged", "events/s"], lines)}
    lines = []
    for t in trajs:
        for k in sorted({int(r["resample"]) for r in ebpf}):
            sel = [r for r in ebpf if r["trajectory"] == t and int(r["resample"]) == k]
            if not sel:
                continue
            p = [float(r["rmse_pos_m"]) * 100 for r in sel]
            q = [float(r["rmse_pos_raw_m"]) * 100 for r in sel]
            lines.append([t, k, len(sel), f"{rms(p):.2f} cm ({max(p):.2f})",
                          f"{rms(q):.2f} cm ({max(q):.2f})",
                          f"{rms([float(r['rmse_rot_deg']) for r in sel]):.2f} deg",
                          f"{np.mean([float(r['best_offset_s']) for r in sel]) * 1e3:+.0f} ms"])
    blocks["ebpf-per-trajectory"] = pagegen.table(
        ["trajectory", "K", "seeds", "position RMSE", "raw", "rotation RMSE",
         "best offset of raw"], lines)
    g0_rows = [r for r in rows if r["method"] == "ebpf_g0"]
    if g0_rows:
        k0 = int(g0_rows[0]["resample"])
        sweep = ebpf + g0_rows
        lines = []
        for g in sorted({float(r["g0"]) for r in sweep}):
            sel = [r for r in sweep if float(r["g0"]) == g and int(r["resample"]) == k0]
            ok = [r for r in sel if r["failed"] == "0"]
            lines.append([f"{g:g}", len(sel), cm(rms([float(r["rmse_pos_m"]) for r in ok]) * 100),
                          cm(rms([float(r["rmse_pos_raw_m"]) for r in ok]) * 100),
                          f"{len(sel) - len(ok)}/{len(sel)}"])
        blocks["ebpf-g0"] = [f"G0 sweep (K = {k0}, every trajectory and seed):", ""] + \
            pagegen.table(["G0", "runs", "position RMSE (not diverged)", "raw", "diverged"], lines)
    return blocks


def slam_rmse(ok):
    """Position [cm] and rotation [deg] RMSE over the runs in ok (NaN without runs)."""
    pos = np.sqrt(np.mean([float(r["rmse_pos_m"]) ** 2 for r in ok])) * 100 if ok else float("nan")
    rot = np.sqrt(np.mean([float(r["rmse_rot_deg"]) ** 2 for r in ok])) if ok else float("nan")
    return pos, rot


def ebslam2d_blocks(rows):
    """EB-SLAM-2D: summary per N beside table 7.1, every run, G0 sweep."""
    slam = [r for r in rows if r["method"] == "ebslam2d"]
    if not slam:
        return {}
    lines = []
    for n in sorted({int(r["particles"]) for r in slam}):
        sel = [r for r in slam if int(r["particles"]) == n]
        ok = [r for r in sel if r["failed"] == "0"]
        pos, rot = slam_rmse(ok)
        eps = np.mean([float(r["events_per_s"]) for r in sel])
        th = THESIS_SLAM.get(n)
        ths = f"{th[0]} cm | {th[1]} deg | {th[2]} | {th[3]:,}" if th else "| | |"
        lines.append([n, f"{pos:.2f} cm", f"{rot:.2f} deg", f"{len(sel) - len(ok)}/{len(sel)}",
                      f"{eps:,.0f}", ths])
    blocks = {"ebslam2d": pagegen.table(
        ["particles", "RMSE pos.", "RMSE rot.", "diverged", "events/s", "thesis: RMSE pos.",
         "RMSE rot.", "failures", "e/s"], lines)}
    blocks["ebslam2d-runs"] = pagegen.table(
        ["trajectory", "N", "seed", "position RMSE", "rotation RMSE", "diverged"],
        [[r["trajectory"], r["particles"], r["seed"], f"{float(r['rmse_pos_m']) * 100:.2f} cm",
          f"{float(r['rmse_rot_deg']):.2f} deg", "yes" if r["failed"] == "1" else "no"]
         for r in slam])
    if any(r["method"] == "ebslam2d_g0" for r in rows):
        sweep = [r for r in slam if int(r["particles"]) == 10] + [
            r for r in rows if r["method"] == "ebslam2d_g0"]
        lines = []
        for g in sorted({float(r["g0"]) for r in sweep}):
            sel = [r for r in sweep if float(r["g0"]) == g]
            ok = [r for r in sel if r["failed"] == "0"]
            pos, rot = slam_rmse(ok)
            lines.append([f"{g:g}", len(sel), "-" if np.isnan(pos) else f"{pos:.2f} cm",
                          "-" if np.isnan(rot) else f"{rot:.2f} deg",
                          f"{len(sel) - len(ok)}/{len(sel)}"])
        blocks["ebslam2d-g0"] = pagegen.table(
            ["G0", "runs", "RMSE pos. (not diverged)", "RMSE rot.", "diverged"], lines)
    return blocks


def speed_block(bench_path):
    """Events per second of EB-PF and EB-SLAM-2D beside the thesis' ({} without the benchmark)."""
    if not bench_path or not os.path.exists(bench_path):
        return {}
    lines = []
    for name, b in median_benchmarks(json.load(open(bench_path))):
        if not (name.startswith("BM_Ebpf") or name.startswith("BM_Ebslam2d")):
            continue  # the filter's speed is in the background-activity section
        parts = dict(p.split(":") for p in name.split("/")[1:] if ":" in p)
        kind = "EB-PF" if name.startswith("BM_Ebpf") else "EB-SLAM-2D"
        eps = b.get("events_per_s", b.get("items_per_second", 0))
        th = b.get("thesis_events_per_s")
        lines.append([kind, parts.get("B"), parts.get("N"), f"{eps:,.0f}",
                      "" if not th else f"{th:,.0f}", f"{eps / th:.1f}x" if th else ""])
    return {"speed": pagegen.table(
        ["filter", "B", "N", "events/s", "thesis events/s", "ratio"], lines)}


def map_figure(runs_dir, t, out_png):
    """The ceiling beside EB-SLAM-2D's map of seed 1; False without them."""
    map_png = os.path.join(runs_dir, t, "slam_N10_s1_map.png")
    ceiling = os.path.join(runs_dir, t, "ceiling.png")
    if not (os.path.exists(map_png) and os.path.exists(ceiling)):
        return False
    m = plt.imread(map_png)
    c = plt.imread(ceiling)
    rows_, cols_ = np.nonzero(m < 0.98)
    fig, ax = plt.subplots(1, 2, figsize=(11, 5))
    ax[0].imshow(c, cmap="gray", origin="upper")
    ax[0].set_title("ceiling texture (1 cm/texel)", fontsize=9)
    if len(rows_):
        m = m[rows_.min():rows_.max() + 1, cols_.min():cols_.max() + 1]
    ax[1].imshow(m, cmap="gray", origin="upper")
    ax[1].set_title("EB-SLAM-2D map M (3 cm cells, dark = likely to fire, map frame)", fontsize=9)
    for x in ax:
        x.set_xticks([])
        x.set_yticks([])
    fig.tight_layout()
    fig.savefig(out_png, dpi=80)
    plt.close(fig)
    return True


def figure_block(runs_dir, trajs, img_dir):
    """Trajectory plots and maps of seed 1 ({} when the runs' trajectories are not there: the
    page keeps its figures)."""
    md = []
    for t in trajs:
        if os.path.exists(os.path.join(runs_dir, t, "ebpf_K25_s1.tum")):
            png = f"{t}_ebpf.png"
            plot_run(runs_dir, t, "ebpf_K25_s1", f"EB-PF {t} (N=50, B=3, K=25, seed 1)",
                     os.path.join(img_dir, png), align=False)
            md += [f"![EB-PF {t}](events2d/{png})", ""]
        if os.path.exists(os.path.join(runs_dir, t, "slam_N10_s1.tum")):
            png = f"{t}_slam.png"
            plot_run(runs_dir, t, "slam_N10_s1", f"EB-SLAM-2D {t} (N=10, seed 1, aligned)",
                     os.path.join(img_dir, png), align=True)
            md += [f"![EB-SLAM-2D {t}](events2d/{png})", ""]
        if map_figure(runs_dir, t, os.path.join(img_dir, f"{t}_map.png")):
            md += [f"![map {t}](events2d/{t}_map.png)", ""]
    return {"figures": md} if md else {}


def main():
    ap = argparse.ArgumentParser()
    ap.add_argument("runs_dir")
    ap.add_argument("--bench", default=None)
    ap.add_argument("--out", default="docs/results")
    ap.add_argument("--command", default="scripts/results/events2d_experiment.sh")
    ap.add_argument("--noise-bench", default=None,
                    help="benchmark JSON with BM_BackgroundActivityFilter (default: --bench)")
    ap.add_argument("--noise-section-only", action="store_true",
                    help="only rewrite the background-activity blocks of the page from runs_dir's "
                         "noise runs (the default-noise runs.csv is the page's)")
    a = ap.parse_args()
    page = os.path.join(a.out, "events2d.md")
    img_dir = os.path.join(a.out, "events2d")
    if a.noise_section_only:
        base = list(csv.DictReader(open(os.path.join(img_dir, "runs.csv"))))
        pagegen.update_page(page, noise_blocks(a.runs_dir, base, a.noise_bench or a.bench,
                                               img_dir))
        return
    os.makedirs(img_dir, exist_ok=True)
    rows = list(csv.DictReader(open(os.path.join(a.runs_dir, "runs.csv"))))
    trajs = sorted({r["trajectory"] for r in rows})
    blocks = {"reproduce": f"`{a.command}`"}
    blocks["runs"] = pagegen.table(
        ["trajectory", "duration", "events"],
        [[t, f"{float(r['duration_s']):.1f} s", f"{int(r['events']):,}"]
         for t in trajs for r in [next(x for x in rows if x["trajectory"] == t)]])
    blocks.update(ebpf_blocks(rows, trajs))
    blocks.update(ebslam2d_blocks(rows))
    blocks.update(noise_blocks(a.runs_dir, rows, a.noise_bench or a.bench, img_dir))
    blocks.update(speed_block(a.bench))
    blocks.update(figure_block(a.runs_dir, trajs, img_dir))
    pagegen.update_page(page, blocks)
    if os.path.abspath(a.runs_dir) != os.path.abspath(img_dir):
        shutil.copy(os.path.join(a.runs_dir, "runs.csv"), os.path.join(img_dir, "runs.csv"))


if __name__ == "__main__":
    main()
