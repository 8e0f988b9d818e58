#!/bin/bash
# Issue 55's table: the coverage planner against the gain planner (both with EB-SLAM-2D in the
# loop, 10 simulated minutes, report render settings) and the random bump-and-turn baseline (40
# simulated minutes, no events) on every layout of src/ebslam/floor_plans and, reported
# separately, the held-out layouts of src/ebslam/floor_plans/held_out, seeds $SEEDS (default 1-5).
# One process per layout and planner, $JOBS at a time (default 2). Builds ebslam_explore (Release
# with debug info) in BUILD_DIR unless $EXPLORE names a built one; then writes the coverage blocks
# of docs/results/exploration.md (scripts/results/coverage_report.py).
#   [SEEDS="1 2 3 4 5"] [JOBS=2] [EXPLORE=path/to/ebslam_explore] \
#     scripts/results/coverage_experiment.sh [BUILD_DIR] [RUNS_DIR]
set -euo pipefail
repo="$(cd "$(dirname "$0")/../.." && pwd)"
source "$repo/scripts/results/explore_runs.sh"
build="${1:-/tmp/build_ebslam_coverage}"
runs="${2:-/tmp/coverage_runs}"
read -r -a seeds <<< "${SEEDS:-1 2 3 4 5}"
njobs="${JOBS:-2}"
explore="${EXPLORE:-}"
if [ -z "${explore}" ]; then
  cmake -S "$repo/src/ebslam" -B "$build" -DCMAKE_BUILD_TYPE=RelWithDebInfo > /dev/null
  cmake --build "$build" -j2 --target ebslam_explore
  explore="$build/ebslam_explore"
fi
rm -rf "$runs"
mkdir -p "$runs"
plans=("$repo"/src/ebslam/floor_plans/*.txt "$repo"/src/ebslam/floor_plans/held_out/*.txt)
# Simulator fidelity for these long runs, as on the rest of the page.
common=(--render-rate 100 --max-step-px 0.5 --seeds "${seeds[@]}")
"${explore}" "${plans[@]}" --baseline-only --duration 2400 "${common[@]}" \
  --output "$runs/baseline" > "$runs/baseline.log"
dirs=(baseline)
for plan in "${plans[@]}"; do
  name="$(basename "${plan}" .txt)"
  for planner in coverage gain; do
    while [ "$(jobs -r | wc -l)" -ge "$njobs" ]; do sleep 1; done
    "${explore}" "${plan}" --planner "${planner}" --duration 600 "${common[@]}" \
      --output "$runs/${planner}_${name}" > "$runs/${planner}_${name}.log" 2>&1 &
    dirs+=("${planner}_${name}")
  done
done
wait
merge_runs "$runs" "${dirs[@]}"
/usr/bin/python3 "$repo/scripts/results/coverage_report.py" "$runs" \
  --plans "$repo/src/ebslam/floor_plans" --held-out "$repo/src/ebslam/floor_plans/held_out" \
  --out "$repo/docs/results" --command "scripts/results/coverage_experiment.sh"
