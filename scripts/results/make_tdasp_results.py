#!/usr/bin/env python3
"""Rewrites the generated blocks of docs/results/tdasp.md (tables, plots) from the output of
make_tdasp_results.sh; the prose of the page is hand-written.

Inputs in --eval: <sequence>.json/.csv (dasp_tdasp), stream.csv and bench.log (dasp_tdasp_bench),
images/<sequence>/frame<k>_{tdasp,sdasp}.png.
"""
import argparse
import csv
import glob
import json
import os
import sys

import matplotlib

matplotlib.use("Agg")
import matplotlib.pyplot as plt  # noqa: E402
import numpy as np  # noqa: E402
from PIL import Image  # noqa: E402

sys.path.insert(0, os.path.dirname(os.path.abspath(__file__)))
import pagegen  # noqa: E402


def read_csv(path):
    with open(path) as f:
        return list(csv.DictReader(f))


def value(row, key):
    v = row.get(key, "")
    return float(v) if v not in ("", None) else None


def mean(values):
    values = [v for v in values if v is not None]
    return sum(values) / len(values) if values else float("nan")


def summary_blocks(per_method):
    """The summary table (means over all frames) and the figures the prose around it quotes."""
    def both(key, fmt_, bold=None):
        t, d = per_method("tdasp", key), per_method("sdasp", key)
        return [("**%s**" if bold == "t" else "%s") % (fmt_ % t),
                ("**%s**" if bold == "s" else "%s") % (fmt_ % d)]

    rows = [["temporal consistency, identity"] + both("consistency_identity", "%.4f", "t"),
            ["temporal consistency, best overlap"] + both("consistency_best_overlap", "%.4f", "s"),
            ["ground truth under the same warp"] + both("consistency_truth", "%.4f"),
            ["segments in the mask"] + both("seg_count", "%.1f"),
            ["segment boundary F1 (2 px)"] + both("seg_boundary_f1", "%.3f"),
            ["segment boundary precision / recall",
             "%.3f / %.3f" % (per_method("tdasp", "seg_boundary_precision"),
                              per_method("tdasp", "seg_boundary_recall")),
             "%.3f / %.3f" % (per_method("sdasp", "seg_boundary_precision"),
                              per_method("sdasp", "seg_boundary_recall"))],
            ["segment ASA"] + both("seg_asa", "%.4f"),
            ["superpixel boundary recall"] + both("sp_boundary_recall", "%.4f"),
            ["superpixel ASA"] + both("sp_asa", "%.4f"),
            ["wall time per frame (shared 2-core machine)"] + both("time_ms", "%.0f ms")]
    return {
        "summary": pagegen.table(["", "t-DASP", "s-DASP independent"], rows),
        "changed-pixels":
            f"Pixels that change segment from one frame to the next: "
            f"{(1 - per_method('sdasp', 'consistency_best_overlap')) * 100:.2f} % for independent "
            f"s-DASP even after the best one-to-one relabelling, "
            f"{(1 - per_method('tdasp', 'consistency_identity')) * 100:.2f} % for t-DASP as it is, "
            f"against {(1 - per_method('tdasp', 'consistency_truth')) * 100:.2f} % for the ground "
            "truth (warp rounding).",
        "streaming":
            f"Per frame on average {per_method('tdasp', 'seeds_kept'):.0f} seeds continued from the "
            f"previous frame, {per_method('tdasp', 'seeds_added'):.0f} added and "
            f"{per_method('tdasp', 'seeds_removed'):.0f} removed by Delta Density Sampling; "
            f"{per_method('tdasp', 'strands_continued'):.0f} strands continued."}


def sequence_blocks(summaries):
    """One line per sequence and the number of sequences t-DASP wins."""
    rows, wins = [], 0
    for s in summaries:
        t, d = s["tdasp"], s["sdasp"]
        win = t["consistency_identity"] > d["consistency_best_overlap"]
        wins += 1 if win else 0
        bold = "**" if win else ""
        rows.append([s["sequence"], f"{bold}{t['consistency_identity']:.4f}{bold}",
                     f"{d['consistency_best_overlap']:.4f}", f"{d['consistency_identity']:.4f}",
                     f"{t['consistency_truth']:.4f}",
                     f"{t['seg_boundary_f1']:.3f} / {d['seg_boundary_f1']:.3f}",
                     f"{t['seg_count']:.1f} / {d['seg_count']:.1f}", f"{t['time_ms']:.0f}",
                     f"{d['time_ms']:.0f}"])
    return {"sequences": pagegen.table(
        ["sequence", "consistency t-DASP (identity)", "s-DASP (best overlap)",
         "s-DASP (identity)", "truth", "F1 t / s", "segments t / s", "t-DASP ms", "s-DASP ms"],
        rows),
        "wins": f"t-DASP's labels as they are are more consistent than independent s-DASP after "
                f"best-overlap matching on {wins} of {len(summaries)} sequences."}


def consistency_plot(rows, summaries, out):
    """Consistency per frame transition (mean over the sequences) and per sequence."""
    fig, axes = plt.subplots(1, 2, figsize=(12, 4))
    n = min(len(r) for r in rows.values()) // 2
    for method, key, label, style in [
        ("tdasp", "consistency_identity", "t-DASP (identity)", "r-"),
        ("tdasp", "consistency_best_overlap", "t-DASP (best overlap)", "r:"),
        ("sdasp", "consistency_best_overlap", "s-DASP independent (best overlap)", "b-"),
        ("sdasp", "consistency_identity", "s-DASP independent (identity)", "b:"),
        ("tdasp", "consistency_truth", "ground truth", "k--"),
    ]:
        curve = []
        for k in range(n - 1):
            curve.append(mean([value(r, key) for seq in rows.values() for r in seq
                               if r["method"] == method and int(r["frame"]) == k]))
        axes[0].plot(range(n - 1), curve, style, label=label)
    axes[0].set_xlabel("frame t (consistency t -> t+1)")
    axes[0].set_ylabel("share of pixels keeping their label")
    axes[0].set_title("temporal label consistency, mean of 8 sequences")
    axes[0].legend(fontsize=8)
    names = [s["sequence"].replace("_freiburg", "\nfr") for s in summaries]
    x = np.arange(len(summaries))
    axes[1].bar(x - 0.2, [s["tdasp"]["consistency_identity"] for s in summaries], 0.4,
                color="r", label="t-DASP (identity)")
    axes[1].bar(x + 0.2, [s["sdasp"]["consistency_best_overlap"] for s in summaries], 0.4,
                color="b", label="s-DASP (best overlap)")
    axes[1].set_xticks(x)
    axes[1].set_xticklabels(names, fontsize=7)
    low = min(min(s["tdasp"]["consistency_identity"], s["sdasp"]["consistency_best_overlap"])
              for s in summaries)
    axes[1].set_ylim(max(0.0, low - 0.05), 1.0)
    axes[1].set_title("per sequence")
    axes[1].legend(fontsize=8)
    fig.tight_layout()
    fig.savefig(os.path.join(out, "tdasp_consistency.png"), dpi=100)
    plt.close(fig)
    return {"consistency-plot": "![consistency](tdasp_consistency.png)"}


def example_block(summaries, eval_dir, out):
    """Frames 0, 10, 20, 29 of the first sequence and of the sequence with the lowest s-DASP
    consistency, t-DASP over s-DASP."""
    image_root = os.path.join(eval_dir, "images")
    examples = []
    if summaries:
        examples.append(summaries[0]["sequence"])
        worst = min(summaries, key=lambda s: s["sdasp"]["consistency_best_overlap"])["sequence"]
        if worst not in examples:
            examples.append(worst)
    md = []
    for index, seq in enumerate(examples):
        strips = []
        for method in ("tdasp", "sdasp"):
            tiles = []
            for k in (0, 10, 20, 29):
                p = os.path.join(image_root, seq, f"frame{k}_{method}.png")
                if os.path.exists(p):
                    tiles.append(np.array(Image.open(p).resize((320, 240))))
            if tiles:
                strips.append(np.hstack(tiles))
        if len(strips) == 2:
            name = f"tdasp_example{index}.png"
            Image.fromarray(np.vstack(strips)).save(os.path.join(out, name))
            what = "the first sequence" if index == 0 else "the sequence where independent s-DASP is least consistent"
            md.append(f"Segments of `{seq}` ({what}), frames 0, 10, 20, 29, one colour per label "
                      "number; top t-DASP, bottom independent s-DASP (its colours change because "
                      "its label numbers do):\n")
            md.append(f"![example {index}]({name})\n")
    return {"examples": md} if md else {}


def stream_blocks(eval_dir, out):
    """The stream bench's console lines, the blocks of 100 frames and the plot over the stream."""
    bench_log = open(os.path.join(eval_dir, "bench.log")).read()
    stream = read_csv(os.path.join(eval_dir, "stream.csv"))
    bench = ["```"] + [line for line in bench_log.splitlines()
                       if line.startswith(("stream", "  ", "BM_", "frame:"))] + ["```"]
    rows = []
    for begin in range(0, len(stream) - 99, 100):
        block = stream[begin:begin + 100]
        times = sorted(float(r["cpu_ms"]) for r in block)
        rows.append([f"{begin}-{begin + 99}", f"{sum(times) / len(times):.1f}",
                     f"{times[len(times) // 2]:.1f}", block[-1]["strands"],
                     f"{int(block[-1]['rss_kb']) / 1024.0:.1f}"])
    frames = [int(r["frame"]) for r in stream]
    cpu = [float(r["cpu_ms"]) for r in stream]
    strands = [int(r["strands"]) for r in stream]
    rss = [int(r["rss_kb"]) / 1024.0 for r in stream]
    fig, axes = plt.subplots(1, 3, figsize=(14, 3.6))
    axes[0].plot(frames, cpu, ".", ms=2)
    window = 25
    if len(cpu) > window:
        smooth = np.convolve(cpu, np.ones(window) / window, mode="valid")
        axes[0].plot(frames[window - 1:], smooth, "r-", label=f"mean of {window}")
        axes[0].legend()
    axes[0].set_xlabel("frame")
    axes[0].set_ylabel("CPU ms per frame")
    axes[0].set_ylim(0, max(cpu) * 1.1)
    axes[1].plot(frames, strands)
    axes[1].set_xlabel("frame")
    axes[1].set_ylabel("strands in the graph")
    axes[2].plot(frames, rss)
    axes[2].set_xlabel("frame")
    axes[2].set_ylabel("resident memory, MB")
    axes[2].set_ylim(0, max(rss) * 1.1)
    fig.tight_layout()
    fig.savefig(os.path.join(out, "tdasp_stream.png"), dpi=100)
    plt.close(fig)
    return {"bench": bench,
            "stream": pagegen.table(["frames", "mean CPU ms", "median CPU ms",
                                     "strands at the block's end", "resident MB at the end"], rows),
            "stream-plot": "![stream](tdasp_stream.png)"}


def main():
    parser = argparse.ArgumentParser()
    parser.add_argument("--eval", required=True)
    parser.add_argument("--out", required=True)
    parser.add_argument("--command", default="scripts/results/make_tdasp_results.sh")
    args = parser.parse_args()
    os.makedirs(args.out, exist_ok=True)

    summaries = [json.load(open(p)) for p in sorted(glob.glob(os.path.join(args.eval, "*.json")))]
    rows = {}
    for s in summaries:
        rows[s["sequence"]] = read_csv(os.path.join(args.eval, s["sequence"] + ".csv"))
    all_rows = [r for seq in rows.values() for r in seq]

    def per_method(method, key):
        return mean([value(r, key) for r in all_rows if r["method"] == method])

    blocks = {"reproduce": "```sh\n%s [build_dir] [data_dir]   # about 15 minutes on 2 cores\n```"
                           % args.command}
    blocks.update(summary_blocks(per_method))
    blocks.update(sequence_blocks(summaries))
    blocks.update(consistency_plot(rows, summaries, args.out))
    blocks.update(example_block(summaries, args.eval, args.out))
    blocks.update(stream_blocks(args.eval, args.out))
    keys = list(summaries[0]["dds_churn_static"].keys())
    blocks["dds"] = pagegen.table(
        ["smoothing (x R)"] + keys,
        [["points removed + added"] + [
            f"{mean([s['dds_churn_static'][k] for s in summaries]) * 100:.1f} %" for k in keys]])
    pagegen.update_page(os.path.join(args.out, "tdasp.md"), blocks)


if __name__ == "__main__":
    main()
