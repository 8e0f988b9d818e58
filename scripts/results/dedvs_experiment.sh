#!/bin/bash
# Regenerates docs/results/dedvs.md and its pictures: builds the ebslam core library
# (RelWithDebInfo) in BUILD_DIR, simulates 3 s of freiburg1_desk as files (dedvs_simulate),
# evaluates the depth fusion on 8 s of each shared freiburg1 hand-held trajectory
# (dedvs_fusion_evaluate), runs the fusion benchmark, the simulated calibration runs
# (dedvs_calibrate, seeds 1-5) and rewrites the page's generated blocks. About 5-8 min on a
# loaded 2-core machine.
#   [SHARED_DATA=../shared/data] scripts/results/dedvs_experiment.sh [BUILD_DIR] [RUNS_DIR]
set -euo pipefail
repo="$(cd "$(dirname "$0")/../.." && pwd)"
build="${1:-/tmp/build_ebslam_dedvs}"
runs="${2:-/tmp/dedvs_runs}"
data="${SHARED_DATA:-$repo/../shared/data}/tum-groundtruth"
mkdir -p "$runs"
cmake -S "$repo/src/ebslam" -B "$build" -DCMAKE_BUILD_TYPE=RelWithDebInfo > /dev/null
cmake --build "$build" -j2 --target ebslam_dedvs_simulate ebslam_dedvs_fusion_evaluate \
  ebslam_dedvs_fusion_bench ebslam_dedvs_calibrate
"$build/ebslam_dedvs_simulate" --trajectory "$data/rgbd_dataset_freiburg1_desk-groundtruth.txt" \
  --t-begin 2 --duration 3 --output "$runs/desk" > "$runs/simulate.txt"
"$build/ebslam_dedvs_fusion_evaluate" \
  --trajectory "$data/rgbd_dataset_freiburg1_desk-groundtruth.txt" \
  "$data/rgbd_dataset_freiburg1_room-groundtruth.txt" \
  "$data/rgbd_dataset_freiburg1_xyz-groundtruth.txt" \
  --t-begin 2 --duration 8 --csv "$runs/fusion.csv" --fused-out "$runs/fused.txt" > "$runs/fusion.md"
"$build/ebslam_dedvs_fusion_bench" --benchmark_repetitions=3 \
  --benchmark_report_aggregates_only=true > "$runs/bench.txt"
"$build/ebslam_dedvs_calibrate" --table-seeds 5 > "$runs/calibration.md"
/usr/bin/python3 "$repo/scripts/results/dedvs_report.py" "$runs" --out "$repo/docs/results"
