#!/usr/bin/python3
"""Rewrites the generated blocks of docs/results/sdasp.md (tables, plots, pictures) from the
dasp_sdasp evaluate/bench output; the prose of the page is hand-written.

Usage: make_sdasp_results.py (--eval EVAL_DIR | --from-page-data) --out docs/results [--command "..."]

EVAL_DIR holds main.json (s-DASP and s-SLIC at the library defaults), grid_sdasp.json and
grid_sslic.json (parameter grids on the same superpixels), lccp.json and lccp_tvoxel.json (PCL
LCCP without / with the single-camera voxel transform), crossval.json (sdasp_crossval.py),
bench.txt (dasp_sdasp_bench output), the example pictures examples/<frame>_<kind>.png and the
worst frames worst/<frame>_{adaptive,global,ucm}.png written by make_sdasp_results.sh. What the
page reads of them is kept in docs/results/sdasp/page_data.json, from which --from-page-data
rewrites the page without the evaluation.
"""
import argparse
import json
import os
import re
import shutil
import sys

import matplotlib

matplotlib.use("Agg")
import matplotlib.pyplot as plt  # noqa: E402

sys.path.insert(0, os.path.dirname(os.path.abspath(__file__)))
import pagegen  # noqa: E402


def load(path):
    with open(path) as f:
        return json.load(f)


def best(results):
    return max(results, key=lambda r: r["ods"]["f1"])


def params(r):
    return "lambda_c %g, lambda_v %g, lambda_n %g, k %d, Theta %d" % (
        r["weight_color"], r["weight_position"], r["weight_normal"], r["eigenvectors"], r["theta"])


CATEGORY_NAMES = [("boxes", "learn 0-16"), ("stacked", "learn 17-24"),
                  ("occluded", "learn 25-32"), ("cylindric", "learn 33-44")]
CV5 = "5 folds (frame index mod 5)"
ADA = "sDASP adaptive lambda_c>=4"
GLO = "sDASP global lambda_c>=4"
CV2 = "even/odd both ways"


def cut_params(p):
    if p.get("cut") == "adaptive":
        cut = "adaptive cut scale %g, quantile %g, max %g" % (
            p["adaptive_scale"], p["adaptive_quantile"], p["adaptive_max_threshold"])
    elif "threshold" in p:
        cut = "threshold %.2f" % p["threshold"]
    else:
        return "seed %.3f m%s" % (p["seed_resolution_m"],
                                  ", -tvoxel" if p["single_camera_transform"] else "")
    if "superpixels" in p:
        return "%s, lambda_c %g, k %d, %s" % (p["superpixels"], p["weight_color"],
                                              p["eigenvectors"], cut)
    return "lambda_c %g, lambda_v %g, lambda_n %g, k %d, %s" % (
        p["weight_color"], p["weight_position"], p["weight_normal"], p["eigenvectors"], cut)


def params_rgb(r):
    return "lambda_c %g, k %d" % (r["weight_color"], r["eigenvectors"])


def fmt(x, digits=3):
    return ("%." + str(digits) + "f") % x


def pr_plot(main_run, sdasp, sslic, sslic_best, sslic_valid_best, lccp_all, out):
    """Precision/recall curves (ODS curves summed over the frames) and the LCCP points."""
    fig, ax = plt.subplots(figsize=(6, 5))
    for r, label, style in [
            (sdasp, "s-DASP (defaults)", dict(color="tab:red")),
            (sslic, "s-SLIC (same defaults)", dict(color="tab:blue", linestyle="--")),
            (sslic_best, "s-SLIC (best of its grid)", dict(color="tab:blue")),
            (sslic_valid_best, "s-SLIC depth-valid (best of its grid)",
             dict(color="tab:purple"))]:
        pts = [p for p in r["curve_threshold_precision_recall_f1"]]
        ax.plot([p[2] for p in pts], [p[1] for p in pts], label="%s, ODS F1 %.3f" % (
            label, r["ods"]["f1"]), **style)
        ax.plot([r["ods"]["recall"]], [r["ods"]["precision"]], "o", color=style["color"])
    a = sdasp["adaptive"][0]
    ax.plot([a["recall"]], [a["precision"]], "*", color="tab:red", markersize=10,
            label="s-DASP adaptive cut (defaults), F1 %.3f" % a["f1"])
    for name, r in lccp_all:
        ax.plot([r["ods"]["recall"]], [r["ods"]["precision"]],
                "^" if "tvoxel" in name else "v", color="tab:green",
                label="%s seed %.3f m, F1 %.3f" % (name, r["lccp_seed_resolution_m"],
                                                   r["ods"]["f1"]))
    for f1 in (0.5, 0.6, 0.7, 0.8, 0.9):
        rs = [f1 / (2 - f1) + i * (1 - f1 / (2 - f1)) / 200 for i in range(201)]
        ps = [f1 * r / (2 * r - f1) for r in rs]
        ax.plot(rs, ps, color="0.85", linewidth=0.7, zorder=0)
    ax.set_xlim(0, 1)
    ax.set_ylim(0, 1)
    ax.set_xlabel("boundary recall (2 px)")
    ax.set_ylabel("boundary precision (2 px)")
    ax.set_title("OSD learn, %d frames, object labels, depth-valid pixels" % main_run["frames"])
    ax.legend(fontsize=7, loc="lower left")
    fig.tight_layout()
    fig.savefig(os.path.join(out, "sdasp_pr.png"), dpi=110)
    plt.close(fig)
    return "![precision/recall](sdasp_pr.png)"


def crossval_blocks(fams):
    """Cross-validated ODS F1 per method family, the folds' choices, the categories."""
    rows = []
    for fam, name in [(ADA, "s-DASP, adaptive cut, lambda_c >= 4 (the defaults' procedure)"),
                      (GLO, "s-DASP, global threshold, lambda_c >= 4"),
                      ("sDASP adaptive", "s-DASP, adaptive cut, whole grid (lambda_c 2-8)"),
                      ("sDASP global", "s-DASP, global threshold, whole grid"),
                      ("LCCP", "LCCP (PCL)"), ("sSLIC", "s-SLIC (both variants)")]:
        e = fams[fam]
        c5, c2 = e["crossval"][CV5], e["crossval"][CV2]
        rows.append([name, "%d" % e["candidates"], "**%s**" % fmt(c5["f1"]),
                     "%s / %s" % (fmt(c5["precision"]), fmt(c5["recall"])), fmt(c2["f1"]),
                     fmt(e["tuned_on_itself"]["f1"]), fmt(c5["gap"])])
    blocks = {"crossval": pagegen.table(
        ["method", "candidates", "**CV ODS F1** (5 folds)", "P / R", "CV ODS F1 (even/odd)",
         "tuned on itself (not held out)", "gap"], rows)}
    ad, gl = fams[ADA], fams[GLO]
    lines = ["- fold %d (frames = %d mod 5 held out): %s (training F1 %s)" % (
        i, i, cut_params(ch["params"]), fmt(ch["train_f1"]))
        for i, ch in enumerate(ad["crossval"][CV5]["fold_choices"])]
    lines.append("- all frames (tuned on itself): %s" % cut_params(ad["tuned_on_itself"]["params"]))
    lines.append("- global threshold, all frames: %s; folds: %s" % (
        cut_params(gl["tuned_on_itself"]["params"]),
        "; ".join("%.2f" % ch["params"]["threshold"]
                  for ch in gl["crossval"][CV5]["fold_choices"])))
    blocks["fold-choices"] = lines
    blocks["categories"] = pagegen.table(
        ["category", "frames", "adaptive cut", "global threshold"],
        [[key, frames_text, fmt(ad["crossval"][CV5]["categories"][key]),
          fmt(gl["crossval"][CV5]["categories"][key])] for key, frames_text in CATEGORY_NAMES])
    return blocks


def worst_block(cv, fams, ev, pictures):
    """The three frames with the lowest held-out F1 of the adaptive cut, with their pictures
    (copied from EVAL_DIR/worst when ev is given, else those beside the page)."""
    frame_f1 = fams[ADA]["crossval"][CV5]["frame_f1"]
    gf = fams[GLO]["crossval"][CV5]["frame_f1"]
    order = sorted(range(len(frame_f1)), key=lambda i: frame_f1[i])
    lines = []
    for i in order[:3]:
        fr = cv["frames"][i]
        cells = []
        for kind in ("adaptive", "global", "ucm"):
            name = "worst_%s_%s.png" % (fr, kind)
            if ev:
                src = os.path.join(ev, "worst", "%s_%s.png" % (fr, kind))
                if os.path.exists(src):
                    shutil.copy(src, os.path.join(pictures, name))
            if os.path.exists(os.path.join(pictures, name)):
                cells.append("![%s %s](sdasp/%s)" % (fr, kind, name))
        lines += ["**%s**, F1 %s (%s)." % (fr, fmt(frame_f1[i]), fmt(gf[i])), "",
                  pagegen.table_row(cells), "|" + "---|" * len(cells), ""]
    return {"worst": lines}


def defaults_blocks(sdasp, sslic, sslic_best, sslic_valid, sslic_valid_best, lccp_all):
    """All frames at the defaults (every setting tuned on itself) and the comparison figures."""
    rows = []

    def row(name, r):
        t = r["time_ms"]
        rows.append([name, "%.0f" % r["mean_superpixels"], "**%s**" % fmt(r["ods"]["f1"]),
                     "%s / %s" % (fmt(r["ods"]["precision"]), fmt(r["ods"]["recall"])),
                     fmt(r["ods"]["threshold"], 2),
                     "%s (%s)" % (fmt(r["ois"]["f1"]), fmt(r["ois"]["mean_frame_best_f1"])),
                     "%.1f (%.1f + %.1f + %.1f + %.1f)" % (
                         t["segmentation_total"], t["superpixels"], t["graph"], t["eigen"],
                         t["labelling"])])

    row("s-DASP (DASP, default graph, best global threshold on these frames)", sdasp)
    a = sdasp["adaptive"][0]
    t = sdasp["time_ms"]
    rows.append(["s-DASP (DASP, defaults: adaptive cut scale %g, quantile %g, max %g)" % (
        a["scale"], a["quantile"], a["max_threshold"]), "%.0f" % sdasp["mean_superpixels"],
        "**%s**" % fmt(a["f1"]), "%s / %s" % (fmt(a["precision"]), fmt(a["recall"])),
        "per frame", "-", "%.1f (%.1f + %.1f + %.1f + %.1f)" % (
            t["segmentation_total"], t["superpixels"], t["graph"], t["eigen"], t["labelling"])])
    row("s-SLIC (ASP_RGB, same defaults)", sslic)
    row("s-SLIC (ASP_RGB, best of its grid: %s)" % params_rgb(sslic_best), sslic_best)
    row("s-SLIC depth-valid (ASP_RGB cut to depth-valid pixels, same defaults)", sslic_valid)
    row("s-SLIC depth-valid (best of its grid: %s)" % params_rgb(sslic_valid_best),
        sslic_valid_best)
    for name, r in lccp_all:
        rows.append(["%s, seed resolution %.3f m" % (name, r["lccp_seed_resolution_m"]),
                     "%.0f supervoxels" % r["mean_supervoxels"], fmt(r["ods"]["f1"]),
                     "%s / %s" % (fmt(r["ods"]["precision"]), fmt(r["ods"]["recall"])), "-",
                     "- (%s mean per frame)" % fmt(r["mean_frame_f1"]),
                     "%.1f" % r["time_ms"]["segmentation_total"]])
    lccp_best_name, lccp_best = max(lccp_all, key=lambda nr: nr[1]["ods"]["f1"])
    sslic_top = max(sslic_best, sslic_valid_best, key=lambda r: r["ods"]["f1"])
    return {
        "defaults": pagegen.table(
            ["method", "superpixels", "F1 (all frames)", "P / R", "ODS threshold", "OIS F1",
             "ms / frame (superpixels + graph + eigen + labelling)"], rows),
        "comparison": "s-DASP ODS F1 %s vs the best LCCP setting %s (%s, seed %.3f m): +%s; vs "
                      "the thesis' 0.76 (its own data set): +%s. s-SLIC reaches %s at best." % (
                          fmt(sdasp["ods"]["f1"]), fmt(lccp_best["ods"]["f1"]), lccp_best_name,
                          lccp_best["lccp_seed_resolution_m"],
                          fmt(sdasp["ods"]["f1"] - lccp_best["ods"]["f1"]),
                          fmt(sdasp["ods"]["f1"] - 0.76), fmt(sslic_top["ods"]["f1"])),
        "ucm-time": "The UCM image (`ultrametricContourMap`) takes %.1f ms for s-DASP." %
                    sdasp["time_ms"]["ucm_image"]}


def bench_block(bench):
    """The bench's medians, ratios and frame line."""
    lines = ["```"]
    medians = "_median " in bench
    for line in bench.splitlines():
        if line.startswith("BM_") and medians and "_median " not in line:
            continue  # repetitions: the medians only
        if line.startswith(("BM_", "K =", "ratio", "DASP +", "frame:")):
            lines.append(line)
    return {"bench": lines + ["```"]}


def grid_blocks(grid_sdasp, sslic_best, sslic_valid_best):
    """The size of the s-DASP grid, its best 10 settings, the spread."""
    ranked = sorted(grid_sdasp["results"], key=lambda r: -r["ods"]["f1"])
    rows = [["%g" % r["weight_color"], "%g" % r["weight_position"], "%g" % r["weight_normal"],
             "%d" % r["eigenvectors"], "%d" % r["theta"], fmt(r["ods"]["f1"]),
             fmt(r["ods"]["threshold"], 2), fmt(max(a["f1"] for a in r["adaptive"])),
             fmt(r["ois"]["f1"])] for r in ranked[:10]]
    worst = ranked[-1]
    return {
        "grid-size": "%d graph/spectral settings on the same DASP superpixels, Theta 4; each with "
                     "every threshold of the curve and %d settings of the adaptive cut." % (
                         len(grid_sdasp["results"]), grid_sdasp["results"][0]["adaptive_settings"]),
        "grid": pagegen.table(["lambda_c", "lambda_v", "lambda_n", "k", "Theta",
                               "ODS F1 (global)", "ODS threshold", "best adaptive cut F1",
                               "OIS F1"], rows),
        "grid-spread": "Spread over the whole grid: ODS F1 %s (worst: %s) to %s. s-SLIC grids "
                       "(colour weight x k; the position and normal terms are absent without "
                       "depth): best %s at %s; depth-valid variant best %s at %s." % (
                           fmt(worst["ods"]["f1"]), params(worst), fmt(ranked[0]["ods"]["f1"]),
                           fmt(sslic_best["ods"]["f1"]), params_rgb(sslic_best),
                           fmt(sslic_valid_best["ods"]["f1"]), params_rgb(sslic_valid_best))}


def examples_block(ev, pictures):
    """Copies the example pictures beside the page (without ev: uses those there); one table row
    per frame."""
    if ev:
        examples = sorted(f for f in os.listdir(os.path.join(ev, "examples")) if f.endswith(".png"))
        for f in examples:
            shutil.copy(os.path.join(ev, "examples", f), os.path.join(pictures, f))
    else:
        examples = sorted(f for f in os.listdir(pictures)
                          if f.endswith(".png") and not f.startswith("worst_"))
    frames = sorted({f.split("_")[0] for f in examples}, key=lambda s: int(re.sub(r"\D", "", s)))
    lines = []
    for fr in frames:
        cells = ["![%s %s](sdasp/%s_%s.png)" % (fr, k, fr, k)
                 for k in ("superpixels", "ucm", "sdasp", "sslic", "lccp")
                 if "%s_%s.png" % (fr, k) in examples]
        lines.append(pagegen.table_row(cells))
        if fr == frames[0]:
            lines.append("|" + "---|" * len(cells))
    return {"examples": lines}


# Per-frame arrays of dasp_sdasp's JSON that the page does not read.
PER_FRAME = ("frame_counts", "adaptive_frame_counts", "adaptive_frame_thresholds", "frame_best_f1")


def strip(result, curve=True):
    r = {k: v for k, v in result.items() if k not in PER_FRAME}
    if not curve:
        r.pop("curve_threshold_precision_recall_f1", None)
    return r


def read_eval(ev):
    """What the page reads from EVAL_DIR (see the module comment), small enough to keep beside the
    page: the grids without their curves and per-frame counts, s-SLIC's best settings only."""
    main_run = load(os.path.join(ev, "main.json"))
    grid_sslic = load(os.path.join(ev, "grid_sslic.json"))["results"]
    with open(os.path.join(ev, "bench.txt")) as f:
        bench = re.sub(r"\x1b\[[0-9;]*m", "", f.read())  # console colours
    return {
        "run": {k: main_run[k] for k in ("frames", "boundary_tolerance_px", "superpixel_count",
                                         "seed")},
        "main": [strip(r) for r in main_run["results"]],
        "grid_sdasp": [dict(strip(r, curve=False), adaptive_settings=len(r["adaptive"]),
                            adaptive=[max(r["adaptive"], key=lambda a: a["f1"])])
                       for r in load(os.path.join(ev, "grid_sdasp.json"))["results"]],
        "sslic_best": [strip(best([r for r in grid_sslic if r["method"] == m]))
                       for m in ("sSLIC", "sSLICvalid")],
        "lccp": [strip(r) for r in load(os.path.join(ev, "lccp.json"))["results"]],
        "lccp_tvoxel": [strip(r) for r in load(os.path.join(ev, "lccp_tvoxel.json"))["results"]],
        "crossval": load(os.path.join(ev, "crossval.json")),
        "bench": bench}


def main():
    ap = argparse.ArgumentParser()
    source = ap.add_mutually_exclusive_group(required=True)
    source.add_argument("--eval", help="the evaluation folder of make_sdasp_results.sh")
    source.add_argument("--from-page-data", action="store_true",
                        help="rewrite the page from OUT/sdasp/page_data.json (what an earlier run "
                             "kept of its evaluation) and the pictures already beside the page")
    ap.add_argument("--out", required=True)
    ap.add_argument("--command", default="scripts/results/make_sdasp_results.sh")
    args = ap.parse_args()
    pictures = os.path.join(args.out, "sdasp")
    os.makedirs(pictures, exist_ok=True)
    page_data = os.path.join(pictures, "page_data.json")
    if args.eval:
        data = read_eval(args.eval)
        with open(page_data, "w") as f:
            json.dump(data, f, separators=(",", ":"))
            f.write("\n")
        for old in os.listdir(pictures):
            if old.startswith("worst_"):
                os.remove(os.path.join(pictures, old))
    else:
        data = load(page_data)
    ev = args.eval
    by_method = {r["method"]: r for r in data["main"]}
    sdasp, sslic, sslic_valid = by_method["sDASP"], by_method["sSLIC"], by_method["sSLICvalid"]
    sslic_best, sslic_valid_best = data["sslic_best"]
    lccp_all = ([("LCCP", r) for r in data["lccp"]] +
                [("LCCP -tvoxel", r) for r in data["lccp_tvoxel"]])
    cv = data["crossval"]
    run = data["run"]
    blocks = {
        "reproduce": "`%s`" % args.command,
        "data": "%d frames; boundary tolerance %d px; K = %d superpixels, seed %d." % (
            run["frames"], run["boundary_tolerance_px"], run["superpixel_count"], run["seed"]),
        "pr": pr_plot(run, sdasp, sslic, sslic_best, sslic_valid_best, lccp_all, args.out)}
    blocks.update(crossval_blocks(cv["families"]))
    blocks.update(worst_block(cv, cv["families"], ev, pictures))
    blocks.update(defaults_blocks(sdasp, sslic, sslic_best, sslic_valid, sslic_valid_best,
                                  lccp_all))
    blocks.update(bench_block(data["bench"]))
    blocks.update(grid_blocks({"results": data["grid_sdasp"]}, sslic_best, sslic_valid_best))
    blocks.update(examples_block(ev, pictures))
    pagegen.update_page(os.path.join(args.out, "sdasp.md"), blocks)


if __name__ == "__main__":
    main()
