#!/bin/bash
# Regenerates docs/results/ebslam3d.md: builds the ebslam core library (Release with debug info)
# in BUILD_DIR, runs EB-SLAM-3D on D-eDVS depth events (simulator + depth fusion) along every
# hand-held TUM path (default and fast sets, three seeds), the parameter sweeps (freiburg1_desk,
# seeds 1-2) and the speed benchmark, and rewrites the page's tables and plots. About an hour on a
# loaded 2-core machine.
#   scripts/results/ebslam3d_experiment.sh [BUILD_DIR] [RUNS_DIR]
set -euo pipefail
repo="$(cd "$(dirname "$0")/../.." && pwd)"
build="${1:-/tmp/build_ebslam_ebslam3d}"
runs="${2:-/tmp/ebslam3d_runs}"
mkdir -p "$runs"
rm -f "$runs/results.jsonl"  # the page is written from this run's results only
cmake -S "$repo/src/ebslam" -B "$build" -DCMAKE_BUILD_TYPE=RelWithDebInfo > /dev/null
cmake --build "$build" -j2 --target ebslam_experiment_ebslam3d ebslam_ebslam3d_bench
"$build/ebslam_ebslam3d_bench" --benchmark_min_time=0.5 --benchmark_repetitions=3 \
  --benchmark_report_aggregates_only=true --benchmark_out="$runs/bench.json" \
  --benchmark_out_format=json
report=(/usr/bin/python3 "$repo/scripts/results/ebslam3d_report.py" --tool "$build/ebslam_experiment_ebslam3d"
  --data "$repo/../shared/data" --runs "$runs" --out "$repo/docs/results" --bench "$runs/bench.json"
  --command "scripts/results/ebslam3d_experiment.sh")
"${report[@]}"  # main table and sweeps (freiburg1_desk seeds 1-2)
# K = 10 is the K sweep's best on the tuning half in the published run: checked on the held-out half.
"${report[@]}" --check-k 10
"${report[@]}" --from-results
# The raw results beside the page, so its tables can be rewritten with --from-results alone.
cp "$runs/results.jsonl" "$runs/bench.json" "$repo/docs/results/ebslam3d/"
