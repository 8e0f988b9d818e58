#!/usr/bin/env bash
# Regenerates docs/results/tdasp.md and its plots: builds the t-DASP tools and bench, renders the
# labelled test videos (4 OSD learn frames, the first of each category: learn0 boxes, learn17
# stacked boxes, learn25 occluded objects, learn33 cylinders; x 2 real trajectories: hand-held
# freiburg1_desk and robot freiburg2_pioneer_360; 30 frames at 30 Hz from 5 s into the
# trajectory, motion scaled by 0.3, Kinect-like noise seeded per sequence), runs t-DASP and
# independent s-DASP over them, runs the 1000-frame stream bench and writes the report.
# Usage: scripts/results/make_tdasp_results.sh [build_dir] [data_dir]
#   STREAM_FRAMES=n  length of the bench stream (default 1000).
set -euo pipefail
REPO="$(cd "$(dirname "${BASH_SOURCE[0]}")/../.." && pwd)"
BUILD="${1:-/tmp/build_tdasp_results}"
DATA="${2:-${REPO}/../shared/data}"
STREAM_FRAMES="${STREAM_FRAMES:-1000}"

cmake -S "${REPO}/src/dasp" -B "${BUILD}" -DCMAKE_BUILD_TYPE=RelWithDebInfo -DBUILD_TESTING=OFF \
  > "${BUILD}.configure.log"
cmake --build "${BUILD}" -j2 --target dasp_render_sequence dasp_tdasp dasp_tdasp_bench
SEQ="${BUILD}/sequences"
EVAL="${BUILD}/eval"
rm -rf "${SEQ}" "${EVAL}"
mkdir -p "${SEQ}" "${EVAL}"
seed=0
for trajectory in freiburg1_desk freiburg2_pioneer_360; do
  for frame in learn0 learn17 learn25 learn33; do
    "${BUILD}/dasp_render_sequence" --folder "${DATA}/osd/learn" --name "${frame}" \
      --trajectory "${DATA}/tum-groundtruth/rgbd_dataset_${trajectory}-groundtruth.txt" \
      --start 5 --frames 30 --fps 30 --motion-scale 0.3 --seed "${seed}" \
      --out "${SEQ}/${frame}_${trajectory}"
    seed=$((seed + 1))
  done
done
"${BUILD}/dasp_tdasp" "${SEQ}"/* --out "${EVAL}" --images "${EVAL}/images" --seed 0 \
  | tee "${EVAL}/tdasp.log"
"${BUILD}/dasp_tdasp_bench" --stream_frames="${STREAM_FRAMES}" \
  --stream_csv="${EVAL}/stream.csv" | tee "${EVAL}/bench.log"
/usr/bin/python3 "${REPO}/scripts/results/make_tdasp_results.py" --eval "${EVAL}" \
  --out "${REPO}/docs/results" --command "scripts/results/make_tdasp_results.sh"
