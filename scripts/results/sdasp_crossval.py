#!/usr/bin/python3
"""Cross-validated parameter choice for s-DASP, its peers LCCP and s-SLIC (boundary ODS F1).

Usage: sdasp_crossval.py --json OUT.json [--min-color-weight W] EVAL.json [EVAL.json ...]

Every EVAL.json is the output of `dasp_sdasp evaluate --per-frame` on the same frames. A
candidate is one complete parameter choice of a method:
  sDASP global   = graph/spectral setting x one threshold of the curve (the same on every frame),
  sDASP adaptive = graph/spectral setting x (scale, quantile, max threshold) of the per-frame cut,
  sSLIC / sSLICvalid = colour weight, k x threshold, LCCP = seed resolution x voxel transform.
Folds by frame index: 5 folds (index mod 5) and even/odd both ways (2 folds). In every fold the
candidate with the best ODS F1 on the training frames (counts summed) is applied to the held-out
frames; the held-out counts of all folds are summed (each frame is held out once) into the
cross-validated ODS precision, recall and F1. "Tuned on itself" = the best candidate on all
frames scored on the same frames. Per frame and per category the held-out counts are kept.
--min-color-weight W adds the s-DASP families restricted to lambda_c >= W ("... lambda_c>=W"): a
prior from outside the learn frames (the synthetic thin-object and touching-box scenes of the
unit tests are segmented right only with the heavier colour term).
"""
import argparse
import json
import re

CATEGORIES = [("boxes", 0, 16), ("stacked", 17, 24), ("occluded", 25, 32), ("cylindric", 33, 44)]


def f1_of(c):
    part, prec, ref, rec = c
    p = prec / part if part else 1.0
    r = rec / ref if ref else 1.0
    return (2 * p * r / (p + r) if p + r > 0 else 0.0), p, r


def add(a, b):
    return [x + y for x, y in zip(a, b)]


def sub(a, b):
    return [x - y for x, y in zip(a, b)]


def collect(evals):
    """{family: [(params, [counts per frame])]} over all input files."""
    families = {}
    frames = None
    for ev in evals:
        names = ev["frame_files"]
        if frames is None:
            frames = names
        elif names != frames:
            raise SystemExit("inputs were evaluated on different frames")
        thresholds = ev["thresholds"]
        for r in ev["results"]:
            m = r["method"]
            if "frame_counts" not in r:
                raise SystemExit("%s result without per-frame counts (--per-frame)" % m)
            if m == "LCCP":
                params = {"seed_resolution_m": r["lccp_seed_resolution_m"],
                          "single_camera_transform": r["lccp_single_camera_transform"]}
                families.setdefault("LCCP", []).append((params, r["frame_counts"]))
                continue
            base = {"weight_color": r["weight_color"], "weight_position": r["weight_position"],
                    "weight_normal": r["weight_normal"], "eigenvectors": r["eigenvectors"],
                    "theta": r["theta"]}
            fam = "%s global" % m if m == "sDASP" else "sSLIC"
            if m != "sDASP":
                base["superpixels"] = r["superpixels"]
            for i, t in enumerate(thresholds):
                p = dict(base, cut="global", threshold=t)
                families.setdefault(fam, []).append(
                    (p, [fc[i] for fc in r["frame_counts"]]))
            if m == "sDASP":
                for a, s in enumerate(r["adaptive"]):
                    p = dict(base, cut="adaptive", adaptive_scale=s["scale"],
                             adaptive_quantile=s["quantile"],
                             adaptive_max_threshold=s["max_threshold"])
                    families.setdefault("sDASP adaptive", []).append(
                        (p, [fc[a] for fc in r["adaptive_frame_counts"]]))
    return families, frames


def crossvalidate(cands, folds, n_frames):
    totals = []
    for _, per_frame in cands:
        t = [0, 0, 0, 0]
        for c in per_frame:
            t = add(t, c)
        totals.append(t)
    held_out = [None] * n_frames
    choices = []
    for test in folds:
        best, best_f1 = None, -1.0
        for k, (_, per_frame) in enumerate(cands):
            t = totals[k]
            for f in test:
                t = sub(t, per_frame[f])
            f1 = f1_of(t)[0]
            if f1 > best_f1:
                best, best_f1 = k, f1
        choices.append({"params": cands[best][0], "train_f1": best_f1})
        for f in test:
            held_out[f] = cands[best][1][f]
    total = [0, 0, 0, 0]
    for c in held_out:
        total = add(total, c)
    f1, p, r = f1_of(total)
    return {"f1": f1, "precision": p, "recall": r, "fold_choices": choices,
            "frame_counts": held_out, "frame_f1": [f1_of(c)[0] for c in held_out]}


def main():
    ap = argparse.ArgumentParser()
    ap.add_argument("evals", nargs="+")
    ap.add_argument("--json", required=True)
    ap.add_argument("--min-color-weight", type=float, default=None)
    args = ap.parse_args()
    evals = []
    for path in args.evals:
        with open(path) as f:
            evals.append(json.load(f))
    families, frames = collect(evals)
    if args.min_color_weight is not None:
        for fam in ("sDASP adaptive", "sDASP global"):
            families["%s lambda_c>=%g" % (fam, args.min_color_weight)] = [
                c for c in families[fam] if c[0]["weight_color"] >= args.min_color_weight]
    n = len(frames)
    schemes = {
        "5 folds (frame index mod 5)": [[f for f in range(n) if f % 5 == k] for k in range(5)],
        "even/odd both ways": [[f for f in range(n) if f % 2 == k] for k in range(2)],
    }
    numbers = [int(re.sub(r"\D", "", name) or -1) for name in frames]
    out = {"frames": frames, "families": {}}
    for fam, cands in families.items():
        totals = []
        for params, per_frame in cands:
            t = [0, 0, 0, 0]
            for c in per_frame:
                t = add(t, c)
            totals.append((f1_of(t), params, t))
        (tf1, tp, tr), tparams, _ = max(totals, key=lambda x: x[0][0])
        entry = {"candidates": len(cands),
                 "tuned_on_itself": {"f1": tf1, "precision": tp, "recall": tr, "params": tparams},
                 "crossval": {}}
        for scheme, folds in schemes.items():
            cv = crossvalidate(cands, folds, n)
            cats = {}
            for name, lo, hi in CATEGORIES:
                c = [0, 0, 0, 0]
                for f in range(n):
                    if lo <= numbers[f] <= hi:
                        c = add(c, cv["frame_counts"][f])
                cats[name] = f1_of(c)[0]
            cv["categories"] = cats
            cv["gap"] = tf1 - cv["f1"]
            del cv["frame_counts"]
            entry["crossval"][scheme] = cv
            print("%-26s %-28s CV ODS F1 %.3f (P %.3f R %.3f), tuned on itself %.3f, gap %.3f" % (
                fam, scheme, cv["f1"], cv["precision"], cv["recall"], tf1, cv["gap"]))
        print("%-26s tuned-on-itself choice: %s" % (fam, tparams))
        out["families"][fam] = entry
    with open(args.json, "w") as f:
        json.dump(out, f, indent=1)


if __name__ == "__main__":
    main()
