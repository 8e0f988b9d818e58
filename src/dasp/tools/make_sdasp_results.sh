#!/usr/bin/env bash
# Regenerates docs/results/sdasp.md, sdasp_pr.png and docs/results/sdasp/*.png: builds dasp_sdasp
# and dasp_sdasp_bench, evaluates s-DASP, s-SLIC (parameter grids included) and PCL LCCP on all
# frames of ../shared/data/osd/learn, runs the bench, draws example pictures, writes the report.
# Everything runs single-threaded, one job after the other.
# Usage: src/dasp/tools/make_sdasp_results.sh [build_dir] [data_dir]
set -euo pipefail
REPO="$(cd "$(dirname "${BASH_SOURCE[0]}")/../../.." && pwd)"
BUILD="${1:-/tmp/build_sdasp_results}"
DATA="${2:-${REPO}/../shared/data/osd/learn}"
EVAL="${BUILD}/sdasp_eval"
EXAMPLES=(learn3 learn21 learn30 learn40)

cmake -S "${REPO}/src/dasp" -B "${BUILD}" -DCMAKE_BUILD_TYPE=RelWithDebInfo > "${BUILD}.configure.log"
cmake --build "${BUILD}" -j2 --target dasp_sdasp dasp_sdasp_bench
mkdir -p "${EVAL}/examples"
SDASP="${BUILD}/dasp_sdasp"

# Library defaults for s-DASP and s-SLIC.
"${SDASP}" evaluate --folder "${DATA}" --json "${EVAL}/main.json" --methods sDASP,sSLIC,sSLICvalid
# Parameter grids on the same superpixels (how the defaults were chosen).
"${SDASP}" evaluate --folder "${DATA}" --json "${EVAL}/grid_sdasp.json" --methods sDASP \
  --color-weight 2,4,8,16 --position-weight 1,2,4 --normal-weight 4,8,16 --eigenvectors 8,16,32 \
  --thresholds 101
"${SDASP}" evaluate --folder "${DATA}" --json "${EVAL}/grid_sslic.json" --methods sSLIC,sSLICvalid \
  --color-weight 2,4,8,16,32,64 --eigenvectors 8,16,32 --thresholds 101
# PCL LCCP with the example's parameters, three supervoxel sizes, without and with -tvoxel.
"${SDASP}" evaluate --folder "${DATA}" --json "${EVAL}/lccp.json" --methods LCCP \
  --lccp-seed-resolutions 0.015,0.02,0.03
"${SDASP}" evaluate --folder "${DATA}" --json "${EVAL}/lccp_tvoxel.json" --methods LCCP \
  --lccp-seed-resolutions 0.015,0.02,0.03 --lccp-single-camera-transform
"${BUILD}/dasp_sdasp_bench" --benchmark_min_time=1 --benchmark_color=false | tee "${EVAL}/bench.txt"

# Example pictures at each method's ODS threshold, half size (s-SLIC: the best variant and setting of its grid).
read -r T_SDASP T_SSLIC C_SSLIC K_SSLIC SP_SSLIC < <(/usr/bin/python3 - "${EVAL}" <<'PY'
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
  "${SDASP}" segment --color "$C" --depth "$D" --threshold "${T_SDASP}" --picture-scale 0.5 \
    --segments "${O}_sdasp.png" --ucm "${O}_ucm.png" --superpixel-overlay "${O}_superpixels.png"
  "${SDASP}" segment --color "$C" --depth "$D" --superpixels "${SP_SSLIC}" --threshold "${T_SSLIC}" \
    --color-weight "${C_SSLIC}" --eigenvectors "${K_SSLIC}" --picture-scale 0.5 \
    --segments "${O}_sslic.png"
  # shellcheck disable=SC2086
  "${SDASP}" lccp --color "$C" --depth "$D" ${LCCP_ARGS} --picture-scale 0.5 \
    --segments "${O}_lccp.png"
done

/usr/bin/python3 "${REPO}/src/dasp/tools/make_sdasp_results.py" --eval "${EVAL}" \
  --out "${REPO}/docs/results" --command "src/dasp/tools/make_sdasp_results.sh"
