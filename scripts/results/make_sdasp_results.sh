#!/usr/bin/env bash
# Regenerates docs/results/sdasp.md, sdasp_pr.png and docs/results/sdasp/*.png: builds dasp_sdasp
# and dasp_sdasp_bench, evaluates s-DASP, s-SLIC (parameter grids included) and PCL LCCP on all
# frames of ../shared/data/osd/learn with per-frame counts, chooses every method's parameters by
# cross-validation over the frames (sdasp_crossval.py), runs the bench, draws example pictures and
# the worst frames, writes the report. Everything runs single-threaded, one job after the other.
# Usage: scripts/results/make_sdasp_results.sh [build_dir] [data_dir]
# REUSE_GRIDS=1 keeps grid/LCCP evaluations already in build_dir/sdasp_eval (they do not depend on
# the library defaults; the defaults run, bench and pictures are always redone).
set -euo pipefail
REPO="$(cd "$(dirname "${BASH_SOURCE[0]}")/../.." && pwd)"
BUILD="${1:-/tmp/build_sdasp_results}"
DATA="${2:-${REPO}/../shared/data/osd/learn}"
EVAL="${BUILD}/sdasp_eval"
EXAMPLES=(learn3 learn21 learn30 learn40)
REUSE_GRIDS="${REUSE_GRIDS:-0}"

cmake -S "${REPO}/src/dasp" -B "${BUILD}" -DCMAKE_BUILD_TYPE=RelWithDebInfo > "${BUILD}.configure.log"
cmake --build "${BUILD}" -j2 --target dasp_sdasp dasp_sdasp_bench
mkdir -p "${EVAL}/examples"
SDASP="${BUILD}/dasp_sdasp"

# Library defaults for s-DASP and s-SLIC.
"${SDASP}" evaluate --folder "${DATA}" --json "${EVAL}/main.json" --methods sDASP,sSLIC,sSLICvalid \
  --per-frame
grid() {  # grid <json> <evaluate arguments...>: skipped with REUSE_GRIDS=1 when the JSON exists
  local json="$1"; shift
  if [ "${REUSE_GRIDS}" = 1 ] && [ -s "${EVAL}/${json}" ]; then echo "reusing ${json}"; return; fi
  "${SDASP}" evaluate --folder "${DATA}" --json "${EVAL}/${json}" --per-frame "$@"
}
# Parameter grids on the same superpixels, every frame's counts kept: s-DASP graph and spectral
# settings x (every threshold of the curve | a grid of the adaptive cut's numbers).
grid grid_sdasp.json --methods sDASP --color-weight 2,4,8 --position-weight 1,2 \
  --normal-weight 4,8,16 --eigenvectors 16,32 --adaptive-scale 4,5,6,7,8,10 \
  --adaptive-quantile 0.5,0.75,0.9 \
  --adaptive-max-threshold 0.08,0.1,0.12,0.15,0.2,0.25,0.3 --thresholds 101
grid grid_sslic.json --methods sSLIC,sSLICvalid --color-weight 2,4,8,16,32,64 \
  --eigenvectors 8,16,32 --thresholds 101
# PCL LCCP with the example's parameters, three supervoxel sizes, without and with -tvoxel.
grid lccp.json --methods LCCP --lccp-seed-resolutions 0.015,0.02,0.03
grid lccp_tvoxel.json --methods LCCP --lccp-seed-resolutions 0.015,0.02,0.03 \
  --lccp-single-camera-transform
# Cross-validated choice (5 folds by frame index mod 5; even/odd both ways) of every method.
/usr/bin/python3 "${REPO}/scripts/results/sdasp_crossval.py" "${EVAL}/grid_sdasp.json" \
  "${EVAL}/grid_sslic.json" "${EVAL}/lccp.json" "${EVAL}/lccp_tvoxel.json" \
  --min-color-weight 4 --json "${EVAL}/crossval.json" | tee "${EVAL}/crossval.txt"
# Adaptive against global cut: five repetitions, interleaved at random, medians.
"${BUILD}/dasp_sdasp_bench" --benchmark_min_time=1 --benchmark_repetitions=5 \
  --benchmark_enable_random_interleaving=true --benchmark_color=false | tee "${EVAL}/bench.txt"

# Example pictures at each method's ODS threshold, half size (s-SLIC: the best variant and setting of its grid).
read -r _ T_SSLIC C_SSLIC K_SSLIC SP_SSLIC < <(/usr/bin/python3 - "${EVAL}" <<'PY'
import json, sys
d = json.load(open(sys.argv[1] + "/main.json"))["results"]
g = max(json.load(open(sys.argv[1] + "/grid_sslic.json"))["results"], key=lambda r: r["ods"]["f1"])
s = [r for r in d if r["method"] == "sDASP"][0]
print(s["ods"]["threshold"], g["ods"]["threshold"], g["weight_color"], g["eigenvectors"],
      g["superpixels"])
PY
)
LCCP_ARGS=$(/usr/bin/python3 - "${EVAL}" <<'PY'
import json, sys
rs = [(r, "") for r in json.load(open(sys.argv[1] + "/lccp.json"))["results"]]
rs += [(r, "--lccp-single-camera-transform") for r in
       json.load(open(sys.argv[1] + "/lccp_tvoxel.json"))["results"]]
r, flag = max(rs, key=lambda x: x[0]["ods"]["f1"])
print("--lccp-seed-resolution %s %s" % (r["lccp_seed_resolution_m"], flag))
PY
)
for f in "${EXAMPLES[@]}"; do
  C="${DATA}/${f}_rgb.png"; D="${DATA}/${f}_depth_mm.png"; O="${EVAL}/examples/${f}"
  "${SDASP}" segment --color "$C" --depth "$D" --picture-scale 0.5 \
    --segments "${O}_sdasp.png" --ucm "${O}_ucm.png" --superpixel-overlay "${O}_superpixels.png"
  "${SDASP}" segment --color "$C" --depth "$D" --superpixels "${SP_SSLIC}" --threshold "${T_SSLIC}" \
    --color-weight "${C_SSLIC}" --eigenvectors "${K_SSLIC}" --picture-scale 0.5 \
    --segments "${O}_sslic.png"
  # shellcheck disable=SC2086
  "${SDASP}" lccp --color "$C" --depth "$D" ${LCCP_ARGS} --picture-scale 0.5 \
    --segments "${O}_lccp.png"
done

# The three frames with the lowest cross-validated F1 of the default (adaptive) cut.
mkdir -p "${EVAL}/worst"
rm -f "${EVAL}/worst/"*.png
WORST=$(/usr/bin/python3 - "${EVAL}" <<'PY'
import json, sys
cv = json.load(open(sys.argv[1] + "/crossval.json"))
f = cv["families"]["sDASP adaptive lambda_c>=4"]["crossval"]["5 folds (frame index mod 5)"]["frame_f1"]
print(" ".join(cv["frames"][i] for i in sorted(range(len(f)), key=lambda i: f[i])[:3]))
PY
)
for f in ${WORST}; do
  C="${DATA}/${f}_rgb.png"; D="${DATA}/${f}_depth_mm.png"; O="${EVAL}/worst/${f}"
  "${SDASP}" segment --color "$C" --depth "$D" --picture-scale 0.5 --segment-overlay "${O}_adaptive.png" \
    --ucm "${O}_ucm.png"
  "${SDASP}" segment --color "$C" --depth "$D" --picture-scale 0.5 --cut global \
    --segment-overlay "${O}_global.png"
done

/usr/bin/python3 "${REPO}/scripts/results/make_sdasp_results.py" --eval "${EVAL}" \
  --out "${REPO}/docs/results" --command "scripts/results/make_sdasp_results.sh"
