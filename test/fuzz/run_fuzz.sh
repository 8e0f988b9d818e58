#!/usr/bin/env bash
# Builds the message fuzz targets (test/fuzz, clang + libFuzzer + ASan + UBSan) and runs each for
# a while from the seed corpus in test/fuzz/corpus, JOBS targets at a time. A crash, a sanitizer
# finding, a leak or a broken promise (abort) fails the target; its input is kept in <build>/findings/. Writes one
# JUnit case per target (for scripts/count_junit.py) and prints executions per target.
#   test/fuzz/run_fuzz.sh [seconds per target (FUZZ_SECONDS, default 15)] [targets...]
# A longer search (e.g. before a release): test/fuzz/run_fuzz.sh 600
# Environment: FUZZ_BUILD (default <repo>/.ws/fuzz), FUZZ_RESULTS (JUnit folder, default
# <build>/test_results), JOBS (default: cores), FUZZ_UPDATE_CORPUS=1 merges new coverage into the
# repository corpus (at most 64 files per target).
set -eo pipefail
here="$(cd "$(dirname "${BASH_SOURCE[0]}")" && pwd)"
repo="$(cd "${here}/../.." && pwd)"
seconds="${1:-${FUZZ_SECONDS:-15}}"
shift || true
build="${FUZZ_BUILD:-${repo}/.ws/fuzz}"
results="${FUZZ_RESULTS:-${build}/test_results}"
jobs="${JOBS:-$(nproc)}"
targets=("$@")
[ ${#targets[@]} -gt 0 ] || targets=(image_fuzzer camera_info_fuzzer event_array_fuzzer
                                     depth_event_array_fuzzer superpixel_array_fuzzer
                                     event_packet_fuzzer)
mkdir -p "${build}" "${results}"
if ! { cmake -S "${here}" -B "${build}" -DCMAKE_C_COMPILER=clang -DCMAKE_CXX_COMPILER=clang++ \
         >"${build}/configure.log" 2>&1 &&
       cmake --build "${build}" -j "${jobs}" --target "${targets[@]}" >"${build}/build.log" 2>&1; }; then
  tail -n 30 "${build}/configure.log" "${build}/build.log"
  echo "fuzz: build failed"
  exit 1
fi
supp="${repo}/test/sanitize"
export ASAN_OPTIONS="halt_on_error=1:detect_leaks=1:suppressions=${supp}/asan.supp"
export LSAN_OPTIONS="suppressions=${supp}/lsan.supp:print_suppressions=0"
export UBSAN_OPTIONS="halt_on_error=1:print_stacktrace=1:suppressions=${supp}/ubsan.supp"
# One target: fuzz it, then write its JUnit case and its summary line to <build>/results/<target>.*.
run_target() {
  local target="$1"
  local work="${build}/corpus/${target}"
  local findings="${build}/findings/${target}"
  mkdir -p "${work}" "${findings}"
  cp -n "${here}/corpus/${target}"/* "${work}/" 2>/dev/null || true
  local log="${build}/${target}.log"
  local start
  start=$(date +%s)
  local target_status=0
  # -rss_limit_mb: a message may not make a conversion hold more than 1 GiB.
  (cd "${findings}" && "${build}/${target}" -max_total_time="${seconds}" -max_len=4096 \
     -rss_limit_mb=1024 -print_final_stats=1 "${work}") >"${log}" 2>&1 || target_status=$?
  local elapsed=$(( $(date +%s) - start ))
  local execs
  execs=$(sed -n 's/^stat::number_of_executed_units: *//p' "${log}" | tail -n 1)
  local line="fuzz: ${target}: ${execs:-0} executions in ${elapsed} s, exit ${target_status}"
  if [ "${target_status}" -ne 0 ]; then
    local reason
    reason=$(grep -m1 -E "ERROR: |runtime error|SUMMARY" "${log}" | sed 's/[<>&"]/ /g' | cut -c1-300 || true)
    line+=$'\n'"fuzz: ${target} FAILED: ${reason} (log ${log}, inputs in ${findings})"
    echo "<testcase classname=\"fuzz\" name=\"${target}\" time=\"${elapsed}\"><failure message=\"${reason}\"/></testcase>" \
      >"${build}/results/${target}.case"
  else
    echo "<testcase classname=\"fuzz\" name=\"${target}\" time=\"${elapsed}\"/>" >"${build}/results/${target}.case"
  fi
  echo "${line}" >"${build}/results/${target}.line"
  if [ "${FUZZ_UPDATE_CORPUS:-0}" = 1 ]; then
    local tmp
    tmp="$(mktemp -d)"
    "${build}/${target}" -merge=1 -max_len=4096 "${tmp}" "${here}/corpus/${target}" "${work}" >/dev/null 2>&1 || true
    if [ "$(ls "${tmp}" | wc -l)" -le 64 ]; then
      rm -f "${here}/corpus/${target}"/*
      cp "${tmp}"/* "${here}/corpus/${target}/"
    fi
    rm -rf "${tmp}"
  fi
}

# The targets run side by side, JOBS at a time (each is one single-threaded process), so that
# fuzzing takes about targets x seconds / JOBS of wall time.
rm -rf "${build}/results"
mkdir -p "${build}/results"
running=0
for target in "${targets[@]}"; do
  if [ "${running}" -ge "${jobs}" ]; then
    wait -n || true
    running=$((running - 1))
  fi
  run_target "${target}" &
  running=$((running + 1))
done
wait || true
status=0
cases=""
failures=0
for target in "${targets[@]}"; do
  if [ ! -f "${build}/results/${target}.case" ]; then
    echo "fuzz: ${target}: no result"
    cases+="<testcase classname=\"fuzz\" name=\"${target}\"><failure message=\"no result\"/></testcase>"
    status=1
    failures=$((failures + 1))
    continue
  fi
  cat "${build}/results/${target}.line"
  if grep -q "<failure" "${build}/results/${target}.case"; then
    status=1
    failures=$((failures + 1))
  fi
  cases+="$(cat "${build}/results/${target}.case")"
done
echo "<?xml version=\"1.0\"?><testsuite name=\"fuzz\" tests=\"${#targets[@]}\" failures=\"${failures}\">${cases}</testsuite>" \
  >"${results}/fuzz.xml"
exit "${status}"
