#!/bin/bash
# Regenerates docs/results/exploration.md: builds the ebslam core library (Release with debug
# info) in BUILD_DIR, runs the gain planner with EB-SLAM-2D on the layouts in $LAYOUTS (default:
# every file of src/ebslam/floor_plans; one process per layout, $JOBS at a time, default 1) for
# the seeds in $SEEDS (default 1-5; 10 simulated minutes each, about 80-100 CPU seconds per run;
# STOP_AT=0.9 ends a run once 90 % are covered) and the random bump-and-turn baseline on every
# layout and the same seeds (40 simulated minutes each; it simulates no events), the benchmark,
# and writes the page.
#   [SEEDS="1 2 3 4 5"] [LAYOUTS="office two_rooms"] [STOP_AT=1] [JOBS=1] \
#     scripts/results/exploration_experiment.sh [BUILD_DIR] [RUNS_DIR]
set -euo pipefail
repo="$(cd "$(dirname "$0")/../.." && pwd)"
source "$repo/scripts/results/explore_runs.sh"
build="${1:-/tmp/build_ebslam_exploration}"
runs="${2:-/tmp/exploration_runs}"
read -r -a seeds <<< "${SEEDS:-1 2 3 4 5}"
read -r -a layouts <<< "${LAYOUTS:-$(cd "$repo/src/ebslam/floor_plans" && ls *.txt | sed 's/\.txt$//' | tr '\n' ' ')}"
njobs="${JOBS:-1}"
stop_at="${STOP_AT:-1}"
cmake -S "$repo/src/ebslam" -B "$build" -DCMAKE_BUILD_TYPE=RelWithDebInfo > /dev/null
cmake --build "$build" -j2 --target ebslam_explore ebslam_exploration_bench
rm -rf "$runs"
mkdir -p "$runs"
# Simulator fidelity for these long runs: render at >= 100 Hz and at most 0.5 px of image motion
# per step (defaults 250 Hz / 0.2 px), which saves a fifth of the CPU time.
common=(--render-rate 100 --max-step-px 0.5 --seeds "${seeds[@]}")
"$build/ebslam_explore" "$repo"/src/ebslam/floor_plans/*.txt --baseline-only --duration 2400 \
  "${common[@]}" --output "$runs/baseline" > "$runs/baseline.log"
dirs=(baseline)
for name in "${layouts[@]}"; do
  while [ "$(jobs -r | wc -l)" -ge "$njobs" ]; do sleep 1; done
  "$build/ebslam_explore" "$repo/src/ebslam/floor_plans/$name.txt" --duration 600 \
    --stop-at "$stop_at" "${common[@]}" --output "$runs/gain_$name" > "$runs/gain_$name.log" &
  dirs+=("gain_$name")
done
wait
merge_runs "$runs" "${dirs[@]}"
"$build/ebslam_exploration_bench" --benchmark_min_time=0.5 \
  --benchmark_out="$runs/bench.json" --benchmark_out_format=json
/usr/bin/python3 "$repo/scripts/results/exploration_report.py" "$runs" --plans "$repo/src/ebslam/floor_plans" \
  --bench "$runs/bench.json" --out "$repo/docs/results" --command "scripts/results/exploration_experiment.sh"
