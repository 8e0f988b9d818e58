#!/bin/bash
# Regenerates docs/results/events2d.md: builds the ebslam core library (Release with debug info)
# in BUILD_DIR, runs the simulated floor-robot experiment (ebslam_experiment_events2d: every
# freiburg2_pioneer_* trajectory, EB-PF and EB-SLAM-2D with several seeds and N = 5, 10, 25,
# 75, G0 sweeps), the background-activity runs (0.3, 1, 3 Hz per pixel, filter and robust start
# on and off, 10 seeds, into RUNS_DIR/noise), the speed benchmark (ebslam_ebpf_bench) and writes
# the report. About 10-15 min on a loaded 2-core machine for the first part; the noise runs take
# about 25 min of CPU (runs that diverge are the slowest), several times that on a loaded machine.
# One noise rate alone (the 3 Hz rows of the page come from such a run), into the page's blocks:
#   ebslam_experiment_events2d --data <shared>/data --out <dir>/r3 --noise-only --noise-rates 3 --noise-seeds 5
#   scripts/results/events2d_report.py <dir> --noise-section-only   (<dir>/*/noise_runs.csv, denoise.csv)
#   scripts/results/events2d_experiment.sh [BUILD_DIR] [RUNS_DIR]
set -euo pipefail
repo="$(cd "$(dirname "$0")/../.." && pwd)"
build="${1:-/tmp/build_ebslam_events2d}"
runs="${2:-/tmp/events2d_runs}"
cmake -S "$repo/src/ebslam" -B "$build" -DCMAKE_BUILD_TYPE=RelWithDebInfo > /dev/null
cmake --build "$build" -j2 --target ebslam_experiment_events2d ebslam_ebpf_bench
"$build/ebslam_experiment_events2d" --data "$repo/../shared/data" --out "$runs" --seeds 3
"$build/ebslam_experiment_events2d" --data "$repo/../shared/data" --out "$runs/noise" --noise-only \
  --noise-rates 0.3,1,3 --noise-seeds 10
"$build/ebslam_ebpf_bench" \
  --benchmark_filter='BM_Ebpf/|BM_Ebslam2d/B:./N:(5|10|25|50|75|100|250)$|BM_BackgroundActivityFilter' \
  --benchmark_min_time=0.3 --benchmark_repetitions=3 --benchmark_report_aggregates_only=true \
  --benchmark_out="$runs/bench.json" --benchmark_out_format=json
/usr/bin/python3 "$repo/scripts/results/events2d_report.py" "$runs" --bench "$runs/bench.json" \
  --out "$repo/docs/results" --command "scripts/results/events2d_experiment.sh"
