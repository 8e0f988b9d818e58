#!/usr/bin/env bash
# Regenerates the tables and plots of docs/results/dasp.md: builds dasp_evaluate, evaluates every
# method on all frames of ../shared/data/osd/learn for K in {250, 500, 1000, 2000}, runs the
# benchmark (kept in docs/results/dasp/bench.txt) and rewrites the page's generated blocks.
# Usage: scripts/results/make_dasp_results.sh [build_dir] [data_dir]
#   JOBS=n   frames evaluated in parallel (default 2); each method itself runs single-threaded.
#   KS="..." superpixel counts (default "250 500 1000 2000").
set -euo pipefail
REPO="$(cd "$(dirname "${BASH_SOURCE[0]}")/../.." && pwd)"
BUILD="${1:-/tmp/build_dasp_results}"
DATA="${2:-${REPO}/../shared/data/osd/learn}"
JOBS="${JOBS:-2}"
read -r -a KS <<< "${KS:-250 500 1000 2000}"
# The superpixels the original DASP delivers in the mask for K = 1000 (the page's reference row):
# DASP also runs at this K, to compare at the same count.
ORIGINAL_COUNT=923

cmake -S "${REPO}/src/dasp" -B "${BUILD}" -DCMAKE_BUILD_TYPE=RelWithDebInfo -DBUILD_TESTING=OFF \
  -DDASP_BUILD_BENCHMARKS=ON > "${BUILD}.configure.log"
cmake --build "${BUILD}" -j"${JOBS}" --target dasp_evaluate dasp_dasp_bench
mkdir -p "${BUILD}/eval"
"${BUILD}/dasp_evaluate" --data "${DATA}" --out "${BUILD}/eval/main" \
  --methods DASP ASP_RGB ASP_RGBD SLIC SEEDS -k "${KS[@]}" -j "${JOBS}"
# DASP with the extra depth weight (DaspConfig::experimental.weight_depth): the trade-off of depth compression
# error against compactness, as methods DASP_wd<w>.
for wd in 0.25 1; do
  "${BUILD}/dasp_evaluate" --data "${DATA}" --out "${BUILD}/eval/dasp_wd${wd}" \
    --methods DASP --dasp-weight-depth "${wd}" --name-suffix "_wd${wd}" -k "${KS[@]}" -j "${JOBS}"
done
# DASP with the former depth-jump ratio, and DASP at the original's count.
"${BUILD}/dasp_evaluate" --data "${DATA}" --out "${BUILD}/eval/dasp_jump0.05" \
  --methods DASP --depth-jump-ratio 0.05 --name-suffix "_jump0.05" -k "${KS[@]}" -j "${JOBS}"
"${BUILD}/dasp_evaluate" --data "${DATA}" --out "${BUILD}/eval/dasp_k${ORIGINAL_COUNT}" \
  --methods DASP -k "${ORIGINAL_COUNT}" -j "${JOBS}"
# DASP with other density clamps (DaspConfig::experimental.max_slant_factor) and more DALIC iterations.
for clamp in 2 3; do
  "${BUILD}/dasp_evaluate" --data "${DATA}" --out "${BUILD}/eval/dasp_slant${clamp}" \
    --methods DASP --max-slant-factor "${clamp}" --name-suffix "_slant${clamp}" -k "${KS[@]}" \
    -j "${JOBS}"
done
for iterations in 10 20; do
  "${BUILD}/dasp_evaluate" --data "${DATA}" --out "${BUILD}/eval/dasp_it${iterations}" \
    --methods DASP --iterations "${iterations}" --name-suffix "_it${iterations}" -k "${KS[@]}" \
    -j "${JOBS}"
done
# DASP with the density's depth exponent below the thesis' 2 (DaspConfig::experimental.depth_exponent), also
# at the original's count.
for exponent in 1 0.5; do
  "${BUILD}/dasp_evaluate" --data "${DATA}" --out "${BUILD}/eval/dasp_exp${exponent}" \
    --methods DASP --depth-exponent "${exponent}" --name-suffix "_exp${exponent}" \
    -k "${KS[@]}" "${ORIGINAL_COUNT}" -j "${JOBS}"
done
# PCL supervoxels are the slowest method: one separate pass per K.
"${BUILD}/dasp_evaluate" --data "${DATA}" --out "${BUILD}/eval/vccs" \
  --methods VCCS -k "${KS[@]}" -j "${JOBS}"
# Speed: every stage, DASP against OpenCV SLIC on the same frame in the same run.
DASP_BENCH_FRAME_DIR="${DATA}" "${BUILD}/dasp_dasp_bench" --benchmark_repetitions=5 \
  --benchmark_report_aggregates_only=true --benchmark_min_time=0.2 > "${BUILD}/bench.txt"
mkdir -p "${REPO}/docs/results/dasp"
cp "${BUILD}/bench.txt" "${REPO}/docs/results/dasp/bench.txt"
/usr/bin/python3 "${REPO}/scripts/results/make_dasp_results.py" --out "${REPO}/docs/results" \
  --bench "${REPO}/docs/results/dasp/bench.txt" --original-count "${ORIGINAL_COUNT}" \
  --command "scripts/results/make_dasp_results.sh" "${BUILD}/eval/main" "${BUILD}/eval/vccs" \
  "${BUILD}/eval/dasp_wd0.25" "${BUILD}/eval/dasp_wd1" "${BUILD}/eval/dasp_jump0.05" \
  "${BUILD}/eval/dasp_k${ORIGINAL_COUNT}" "${BUILD}/eval/dasp_slant2" "${BUILD}/eval/dasp_slant3" \
  "${BUILD}/eval/dasp_it10" "${BUILD}/eval/dasp_it20" "${BUILD}/eval/dasp_exp1" \
  "${BUILD}/eval/dasp_exp0.5"
