#!/usr/bin/python3
"""Rewrites the generated blocks of docs/results/dasp.md (tables, plots, benchmark) from
dasp_evaluate output folders; the prose of the page is hand-written.

Usage: make_dasp_results.py --out docs/results [--command "..."] EVAL_DIR [EVAL_DIR ...]

Every EVAL_DIR holds the mean.csv / mean.json written by dasp_evaluate (e.g. one run for the
DASP family and the OpenCV peers, one for PCL VCCS). Rows of all folders are merged; a method
that appears in two folders keeps the rows of the later folder.
"""
import argparse
import csv
import json
import os
import re
import sys

import matplotlib

matplotlib.use("Agg")
import matplotlib.pyplot as plt  # noqa: E402

sys.path.insert(0, os.path.dirname(os.path.abspath(__file__)))
import pagegen  # noqa: E402

METHOD_ORDER = ["DASP", "ASP_RGB", "ASP_RGBD", "SLIC", "SEEDS", "VCCS"]
STYLE = {
    "DASP": dict(color="tab:red", marker="o"),
    "ASP_RGB": dict(color="tab:blue", marker="s"),
    "ASP_RGBD": dict(color="tab:purple", marker="D"),
    "SLIC": dict(color="tab:green", marker="^"),
    "SEEDS": dict(color="tab:olive", marker="v"),
    "VCCS": dict(color="tab:orange", marker="P"),
    "DASP_wd0.25": dict(color="tab:red", marker="o", linestyle="--", alpha=0.6),
    "DASP_wd1": dict(color="tab:red", marker="o", linestyle=":", alpha=0.6),
    "DASP_jump0.05": dict(color="tab:brown", marker="o", linestyle="--", alpha=0.6),
}
# Variants that appear only in their own tables, not in the plots and the tables of all methods
# (they would crowd them).
TABLE_ONLY = ("DASP_slant", "DASP_it", "DASP_exp")
# (column, title, better) for the plots.
PLOTS = [
    ("boundary_recall", "Boundary recall (2 px)", "higher"),
    ("ue_np", "Undersegmentation error (Neubert-Protzel)", "lower"),
    ("use_thesis", "Undersegmentation error (thesis def. 14)", "lower"),
    ("asa", "Achievable segmentation accuracy", "higher"),
    ("ce_depth_mm", "Compression error depth [mm]", "lower"),
    ("ev_depth", "Explained variation depth", "higher"),
    ("ce_color", "Compression error colour [0..255]", "lower"),
    ("co_ipq", "Compactness CO (isoperimetric quotient)", "higher"),
    ("ipq_3d", "3D isoperimetric quotient", "higher"),
    ("disconnected_fraction", "Fraction of disconnected superpixels", "lower"),
    ("count_ratio", "Delivered / requested superpixels", "1 is exact"),
    ("time_ms", "Time per frame [ms], one core", "lower"),
]

# The columns of the tables of one DASP parameter.
QUALITY_COLUMNS = [("boundary_recall", "Rec", 4), ("ue_np", "UE NP", 5), ("asa", "ASA", 5),
                   ("ce_depth_mm", "CE depth mm", 2), ("co_ipq", "CO", 3)]


def read_means(folders):
    rows = {}
    meta = []
    for folder in folders:
        with open(os.path.join(folder, "mean.csv"), newline="") as f:
            for row in csv.DictReader(f):
                key = (row["method"], int(row["k"]))
                rows[key] = {k: (float(v) if k not in ("method",) and v != "" else v)
                             for k, v in row.items()}
        meta_path = os.path.join(folder, "mean.json")
        if os.path.exists(meta_path):
            with open(meta_path) as f:
                m = json.load(f)
            m.pop("means", None)
            meta.append((folder, m))
    return rows, meta


def methods_of(rows):
    present = {m for m, _ in rows}
    return [m for m in METHOD_ORDER if m in present] + sorted(present - set(METHOD_ORDER))


def fmt(v, digits):
    return "" if v == "" else f"{v:.{digits}f}"


def variant_table(rows, ks, methods, columns):
    """Markdown table with one line per K and method (in the order given) that has a row;
    columns: (column, header, digits)."""
    return pagegen.table(["K", "method"] + [h for _, h, _ in columns],
                         [[k, m] + [fmt(r.get(c, ""), d) for c, _, d in columns]
                          for k in ks for m in methods for r in [rows.get((m, k))] if r]) + [""]


# The reference row of the thesis author's original DASP (K = 1000, 923 superpixels in the
# mask): (column, name, value, the better direction, digits).
ORIGINAL_ROW = [("boundary_recall", "Rec", 0.984, "higher", 3),
                ("ue_np", "UE", 0.0037, "lower", 4),
                ("asa", "ASA", 0.9982, "higher", 4),
                ("ce_depth_mm", "CE depth", 6.9, "lower", 2),
                ("co_ipq", "CO", 0.95, "higher", 3)]
QUALITY_PEERS = ["ASP_RGB", "SLIC", "VCCS"]


def bench_figures(lines):
    """The headline figures of the bench console output (ratio None, dicts empty where
    the lines are missing)."""
    figures = {"ratio": None, "k": {}, "pixels": {}, "slic_pixels": {}}
    for line in lines:
        m = re.search(r"alternating frames, CPU time: ([0-9.]+)", line)
        if m:
            figures["ratio"] = float(m.group(1))
        m = re.match(r"^\s+K =\s*(\d+): DASP\s+[0-9.]+ ms \(x([0-9.]+)\), OpenCV SLIC\s+[0-9.]+ ms "
                     r"\(x([0-9.]+)\)", line)
        if m:
            figures["k"][int(m.group(1))] = (float(m.group(2)), float(m.group(3)))
        m = re.match(r"^\s+([0-9.]+)x the pixels:.*time x([0-9.]+), time per pixel x([0-9.]+)",
                     line)
        if m:
            figures["pixels"][float(m.group(1))] = (float(m.group(2)), float(m.group(3)))
            m_slic = re.search(r"OpenCV SLIC\s+[0-9.]+ ms, time per pixel x([0-9.]+)", line)
            if m_slic:
                figures["slic_pixels"][float(m.group(1))] = float(m_slic.group(1))
    return figures


def summary_table(rows, ks, original_count, bench_lines):
    """Markdown lines: the headline figures of the tables and the benchmark below."""
    lines = ["| property | measured |", "|---|---|"]
    bench = bench_figures(bench_lines)
    if bench["ratio"] is not None:
        lines.append(f"| single-threaded DASP / OpenCV SLIC time, same frame, same run | "
                     f"{bench['ratio']:.3f} (alternating frames, CPU time) |")
    if bench["pixels"]:
        scales = sorted(bench["pixels"])
        per_pixel = [bench["pixels"][x][1] for x in scales]
        slic = [bench["slic_pixels"][x] for x in scales if x in bench["slic_pixels"]]
        peer = (" (OpenCV SLIC on the same frames: " + " / ".join(f"x{v:.2f}" for v in slic) + ")"
                if len(slic) == len(scales) else "")
        lines.append("| time per pixel against the pixel count | time per pixel " +
                     " / ".join(f"x{v:.2f}" for v in per_pixel) + " at " +
                     " / ".join(f"{x:g}x" for x in scales) + " the pixels" + peer + " |")
    if bench["k"]:
        kk = sorted(bench["k"])
        dasp = [bench["k"][k][0] for k in kk]
        slic = [bench["k"][k][1] for k in kk]
        lines.append("| time against K | DASP " + " / ".join(f"x{v:.2f}" for v in dasp) +
                     f" at K = {' / '.join(str(k) for k in kk)} (OpenCV SLIC x{min(slic):.2f} to "
                     f"x{max(slic):.2f}) |")
    quality_ks = [k for k in ks if ("DASP", k) in rows]
    if quality_ks:
        worst = max(abs(rows[("DASP", k)]["superpixels"] / k - 1.0) for k in quality_ks)
        lines.append(f"| delivered superpixels against the requested K | largest deviation "
                     f"{100 * worst:.2f} % (K = {', '.join(str(k) for k in quality_ks)}) |")
        fractions = [rows[("DASP", k)].get("disconnected_fraction", "") for k in quality_ks]
        if "" not in fractions:  # older evaluations lack the column: no line rather than a guess
            lines.append(f"| superpixels in more than one piece | largest fraction: "
                         f"{max(fractions):.4f} |")
        for column, name, digits in (("ue_np", "undersegmentation error (NP)", 4),
                                     ("ce_depth_mm", "depth compression error (mm)", 2)):
            misses = []
            for k in quality_ks:
                ours = rows[("DASP", k)][column]
                for peer in QUALITY_PEERS:
                    theirs = rows.get((peer, k), {}).get(column, "")
                    if theirs != "" and not ours < theirs:
                        misses.append(f"K = {k}: {ours:.{digits}f} against {peer} "
                                      f"{theirs:.{digits}f}")
            peers = [p for p in QUALITY_PEERS if any((p, k) in rows for k in quality_ks)]
            lines.append(f"| DASP's {name} against {', '.join(peers)} | " +
                         ("below all at every K" if not misses else "not below at " +
                          "; ".join(misses)) + " |")
    r = rows.get(("DASP", original_count))
    if r:
        parts = []
        for column, name, value, better, digits in ORIGINAL_ROW:
            ours = r[column]
            good = ours >= value if better == "higher" else ours <= value
            parts.append(f"{name} {ours:.{digits}f} against {value:g}" +
                         ("" if good else " (worse)"))
        lines.append(f"| DASP against the original DASP at its count (K = {original_count}) | " +
                     ", ".join(parts) + " |")
    return lines


def plot(rows, ks, methods, out_dir):
    files = []
    fig, axes = plt.subplots(3, 4, figsize=(18, 12))
    for ax, (col, title, better) in zip(axes.flat, PLOTS):
        for m in methods:
            pts = [(k, rows[(m, k)].get(col, "")) for k in ks if (m, k) in rows]
            pts = [(k, v) for k, v in pts if v != ""]
            if not pts:
                continue
            ax.plot([p[0] for p in pts], [p[1] for p in pts], label=m, **STYLE.get(m, {}))
        ax.set_xscale("log", base=2)
        ax.set_xticks(ks)
        ax.set_xticklabels([str(k) for k in ks])
        ax.set_xlabel("requested superpixels K")
        ax.set_title(f"{title} ({better})", fontsize=10)
        ax.grid(True, alpha=0.3)
        if col in ("time_ms",):
            ax.set_yscale("log")
    axes.flat[0].legend(fontsize=9)
    fig.tight_layout()
    path = os.path.join(out_dir, "dasp_metrics_vs_k.png")
    fig.savefig(path, dpi=80)
    plt.close(fig)
    files.append(path)
    # The four metrics of thesis fig. 3.13 against the delivered number of superpixels.
    fig, axes = plt.subplots(1, 4, figsize=(18, 4.2))
    for ax, (col, title) in zip(axes, [("boundary_recall", "Boundary recall (2 px)"),
                                       ("ue_np", "UE (Neubert-Protzel)"),
                                       ("ev_depth", "Explained variation depth"),
                                       ("ce_depth_mm", "Compression error depth [mm]")]):
        for m in methods:
            pts = [(rows[(m, k)]["superpixels_in_mask"], rows[(m, k)][col]) for k in ks
                   if (m, k) in rows and rows[(m, k)].get(col, "") != ""]
            if pts:
                ax.plot([p[0] for p in pts], [p[1] for p in pts], label=m, **STYLE.get(m, {}))
        ax.set_xscale("log")
        ax.set_xlabel("superpixels inside the mask (delivered)")
        ax.set_title(title, fontsize=10)
        ax.grid(True, alpha=0.3)
    axes[0].legend(fontsize=9)
    fig.tight_layout()
    path = os.path.join(out_dir, "dasp_fig313_vs_count.png")
    fig.savefig(path, dpi=80)
    plt.close(fig)
    files.append(path)
    return files


def anchor_blocks(rows, listed, original_count):
    """K = 1000 for every method, the reference row and DASP at the original's count."""
    lines = pagegen.table(
        ["method", "superpixels delivered (K = 1000)", "superpixels in mask", "Rec", "UE", "ASA",
         "CE depth", "CO", "time per frame"],
        [[m, f"{r['superpixels']:.0f}", f"{r['superpixels_in_mask']:.0f}",
          f"{r['boundary_recall']:.3f}", f"{r['ue_np']:.4f}", f"{r['asa']:.4f}",
          f"{r['ce_depth_mm']:.1f} mm", f"{r['co_ipq']:.2f}", f"{r['time_ms']:.0f} ms"]
         for m in listed for r in [rows.get((m, 1000))] if r])
    original = ", ".join(f"{name} {value:g}" + (" mm" if column == "ce_depth_mm" else "")
                         for column, name, value, _, _ in ORIGINAL_ROW)
    blocks = {"anchor": lines,
              "reference": f"Original DASP K = 1000: 923 in mask, {original}, about 60 ms."}
    r = rows.get(("DASP", original_count))
    if r:
        blocks["original-count"] = (
            f"DASP asked for K = {original_count}: {r['superpixels_in_mask']:.0f} in mask, Rec "
            f"{r['boundary_recall']:.3f}, UE {r['ue_np']:.4f}, ASA {r['asa']:.4f}, CE depth "
            f"{r['ce_depth_mm']:.2f} mm, CO {r['co_ipq']:.3f}.")
    return blocks


def exponent_lines(rows, ks, exponents, original_count):
    """Each depth exponent against the original DASP's row and against PCL VCCS."""
    md = []
    for m in exponents:
        r = rows.get((m, original_count))
        if r:
            worse = [name for c, name, value, better, _ in ORIGINAL_ROW
                     if (float(r[c]) < value if better == "higher" else float(r[c]) > value)]
            md.append(f"- {m} at K = {original_count} against the original DASP's row: " +
                      ("at least as good on every column" if not worse
                       else "worse on " + ", ".join(worse)) + ".")
        above = [f"K = {k}: {float(rows[(m, k)]['ce_depth_mm']):.2f} against "
                 f"{float(rows[('VCCS', k)]['ce_depth_mm']):.2f}"
                 for k in ks if (m, k) in rows and ("VCCS", k) in rows and
                 float(rows[(m, k)]["ce_depth_mm"]) >= float(rows[("VCCS", k)]["ce_depth_mm"])]
        md.append(f"- {m}, depth CE against PCL VCCS: " +
                  ("below at every K" if not above else "not below at " + "; ".join(above)) + ".")
    return md


def variant_blocks(rows, ks, methods, original_count):
    """One table per DASP parameter varied (weight_depth, depth_jump_ratio, max_slant_factor,
    depth_exponent, iterations)."""
    def family(prefix, key=float, reverse=False):
        found = [m for m in methods if m.startswith(prefix)]
        return sorted(found, key=lambda m: key(m[len(prefix):]), reverse=reverse) \
            if key else found

    blocks = {}
    weights = family("DASP_wd", key=None)
    if weights:
        vccs_co = [rows[("VCCS", k)]["co_ipq"] for k in ks if ("VCCS", k) in rows]
        blocks["weight-depth-vccs"] = (f"VCCS: CO {min(vccs_co):.2f}-{max(vccs_co):.2f} over these K."
                                       if vccs_co else "")
        blocks["weight-depth"] = variant_table(
            rows, ks, ["VCCS", "DASP"] + weights,
            [("superpixels_in_mask", "in mask", 0), ("ce_depth_mm", "CE depth mm", 2),
             ("ce_position_mm", "CE 3D mm", 2), ("co_ipq", "CO", 3),
             ("boundary_recall", "Rec", 3), ("ue_np", "UE NP", 4)])
    jumps = family("DASP_jump", key=None)
    if jumps:
        blocks["jump"] = variant_table(rows, ks, ["DASP"] + jumps, QUALITY_COLUMNS)
    slants = family("DASP_slant")
    if slants:
        blocks["slant"] = variant_table(rows, ks, ["VCCS", "DASP"] + slants,
                                        [("superpixels_in_mask", "in mask", 0)] + QUALITY_COLUMNS)
    exponents = family("DASP_exp", reverse=True)
    if exponents:
        blocks["exponent"] = variant_table(
            rows, sorted(ks + [original_count]), ["VCCS", "DASP"] + exponents,
            [("superpixels_in_mask", "in mask", 0)] + QUALITY_COLUMNS + [("time_ms", "ms", 0)]) + \
            exponent_lines(rows, ks, exponents, original_count)
    iterations = family("DASP_it", key=int)
    if iterations:
        blocks["iterations"] = variant_table(rows, ks, ["DASP"] + iterations,
                                             QUALITY_COLUMNS + [("time_ms", "ms", 0)])
    return blocks


def all_metrics_block(rows, ks, listed):
    """Every metric of every method (not the variants) and K."""
    cols = [("superpixels", "delivered", 0), ("superpixels_in_mask", "in mask", 0),
            ("boundary_recall", "Rec", 3), ("boundary_f1", "boundary F1", 3),
            ("ue_np", "UE NP", 4), ("use_thesis", "USE thesis", 4), ("asa", "ASA", 4),
            ("ce_depth_mm", "CE depth mm", 2), ("ce_position_mm", "CE 3D mm", 2),
            ("ce_color", "CE colour", 2), ("ce_normal", "CE normal", 3),
            ("ev_depth", "EV depth", 4), ("ev_color", "EV colour", 3),
            ("co_ipq", "CO", 3), ("ipq_3d", "IPQ 3D", 3), ("cq", "CQ", 4),
            ("disconnected_fraction", "disconnected", 4), ("ude_relative", "UDE rel", 3),
            ("time_ms", "ms", 0)]
    return {"all-metrics": pagegen.table(
        ["method", "K"] + [c[1] for c in cols],
        [[m, k] + [fmt(r.get(c, ""), d) for c, _, d in cols]
         for m in listed for k in ks for r in [rows.get((m, k))] if r])}


def kept_bench_lines(bench_lines):
    """The lines of the bench console output the page shows: medians, ratios, derived tables."""
    return [line for line in bench_lines if "_median" in line or line.startswith("ratio")
            or line.startswith("peak memory") or line.startswith("Benchmark")
            or line.startswith("runtime against") or line.startswith("DASP stages")
            or re.match(r"^\s+K = ", line) or re.match(r"^\s+features\s", line)
            or re.match(r"^\s+[0-9.]+x the pixels", line)]


def k_growth_text(keep):
    """Label runs against K from the stage table (its rows: K, eight stage times, runs)."""
    runs = {}
    for line in keep:
        m = re.match(r"^\s+K =\s*(\d+)((?:\s+[0-9.]+){9})$", line)
        if m:
            runs[int(m.group(1))] = float(m.group(2).split()[-1])
    if not runs and any(line.startswith("DASP stages") for line in keep):
        raise SystemExit("the bench's 'DASP stages' table has no rows of a K and nine numbers "
                         "(stage times and label runs): its columns changed, update the parser")
    if len(runs) < 2:
        return None
    k_lo, k_hi = min(runs), max(runs)
    return (f"Label runs x{runs[k_hi] / runs[k_lo]:.1f} from K = {k_lo} to {k_hi} "
            f"({runs[k_lo]:.0f} to {runs[k_hi]:.0f}).")


def pixel_growth_text(keep, bench_lines):
    """Stage times per 640x480 worth of pixels, smallest against largest frame."""
    stage_names = ["features", "density", "sampling", "init", "assign", "update",
                   "connectivity", "fit"]
    per_scale = {}
    for line in keep:
        m = re.match(r"^\s+([0-9.]+)x the pixels((?:\s+[0-9.]+){9})$", line)
        if m:
            per_scale[float(m.group(1))] = [float(v) for v in m.group(2).split()]
    bench = bench_figures(bench_lines)
    if not (1.0 in per_scale and len(per_scale) >= 2 and bench["slic_pixels"]):
        return None
    top = max(per_scale)
    base, big = per_scale[1.0], per_scale[top]
    growth = sorted(((big[i] - base[i], stage_names[i]) for i in range(8)), reverse=True)
    total = sum(big[:8]) - sum(base[:8])
    listed = ", ".join(f"{name} {base[stage_names.index(name)]:.2f} to "
                       f"{big[stage_names.index(name)]:.2f} ms" for _, name in growth[:3])
    runs_per = [v[8] for v in per_scale.values()]
    return (f"From 1x to {top:g}x the pixels the sum of the stages per 640x480 worth of pixels "
            f"grows by {total:.2f} ms, most in {listed}. The label runs per 640x480 range from "
            f"{min(runs_per):.0f} to {max(runs_per):.0f} (x{max(runs_per) / min(runs_per):.2f}). "
            f"OpenCV SLIC per pixel: x{bench['slic_pixels'].get(top, float('nan')):.2f} at "
            f"{top:g}x.")


def bench_blocks(bench_lines):
    """The bench's kept lines and the figures the speed prose quotes ({} without a bench)."""
    if not bench_lines:
        return {}
    keep = kept_bench_lines(bench_lines)
    blocks = {"bench": ["```"] + keep + ["```"]}
    k_growth = k_growth_text(keep)
    if k_growth:
        blocks["k-growth"] = k_growth
    pixel_growth = pixel_growth_text(keep, bench_lines)
    if pixel_growth:
        blocks["pixel-growth"] = pixel_growth
    return blocks


def main():
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--out", required=True, help="output folder (docs/results)")
    parser.add_argument("--command", default="scripts/results/make_dasp_results.sh",
                        help="command line to quote in the report")
    parser.add_argument("--bench", default=None,
                        help="console output of dasp_dasp_bench (its medians and tables)")
    parser.add_argument("--original-count", type=int, default=0,
                        help="K of the DASP run at the count the original DASP delivers for "
                             "K = 1000: reported beside the reference, not in the tables over K")
    parser.add_argument("folders", nargs="+")
    args = parser.parse_args()
    os.makedirs(args.out, exist_ok=True)
    rows, meta = read_means(args.folders)
    if not rows:
        raise SystemExit("no rows in " + " ".join(args.folders))
    ks = sorted({k for _, k in rows} - {args.original_count})
    methods = methods_of(rows)
    listed = [m for m in methods if not m.startswith(TABLE_ONLY)]  # plots, tables of all methods
    plots = plot(rows, ks, listed, args.out)
    frames = sorted({int(m.get("frames", 0)) for _, m in meta})
    main_meta = next((m for f, m in meta if os.path.basename(f.rstrip("/")) == "main"), {})
    bench_lines = ([re.sub(r"\x1b\[[0-9;]*m", "", line.rstrip())
                    for line in open(args.bench, encoding="utf-8")]
                   if args.bench and os.path.exists(args.bench) else [])
    blocks = {
        "reproduce": f"```\n{args.command} [build_dir] [data_dir]\n```",
        "frames": f"Frames evaluated: {', '.join(str(f) for f in frames)}; DASP depth-jump ratio "
                  f"{float(main_meta.get('depth_jump_ratio', 0.05)):.3g}, "
                  f"{int(main_meta.get('iterations', 5))} DALIC iterations.",
        "summary": summary_table(rows, ks, args.original_count, bench_lines),
        "plots": [f"![{os.path.basename(p)}]({os.path.basename(p)})\n" for p in plots],
        "runs": [f"- run `{os.path.basename(folder.rstrip('/'))}`: " +
                 ", ".join(f"{k} = {v:.6g}" if isinstance(v, float) else f"{k} = {v}"
                           for k, v in m.items() if k != "data") for folder, m in meta]}
    blocks.update(anchor_blocks(rows, listed, args.original_count))
    blocks.update(variant_blocks(rows, ks, methods, args.original_count))
    blocks.update(all_metrics_block(rows, ks, listed))
    blocks.update(bench_blocks(bench_lines))
    pagegen.update_page(os.path.join(args.out, "dasp.md"), blocks)
    print("wrote", ", ".join(plots))


if __name__ == "__main__":
    main()
