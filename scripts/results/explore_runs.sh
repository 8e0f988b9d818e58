# Sourced by the exploration experiment scripts.
# merge_runs RUNS_DIR DIR...: one summary.csv in RUNS_DIR from the runs in RUNS_DIR/DIR/ (each
# ebslam_explore --output), and their per-run files copied next to it for the report.
merge_runs() {
  local runs="$1"
  shift
  {
    head -1 "$runs/$1/summary.csv"
    local d
    for d in "$@"; do
      tail -n +2 "$runs/$d/summary.csv"
      cp "$runs/$d"/*_* "$runs"/
    done
  } > "$runs/summary.csv.tmp"
  mv "$runs/summary.csv.tmp" "$runs/summary.csv"
}
