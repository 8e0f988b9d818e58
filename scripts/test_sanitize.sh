#!/usr/bin/env bash
# `make test-sanitize`: builds the ROS-free core libraries (src/ebslam, src/dasp, src/edvs) in
# Debug with AddressSanitizer and UndefinedBehaviorSanitizer (test/sanitize/) and runs their
# tests under them. Any sanitizer finding fails its test; known false alarms of uninstrumented
# Debian libraries are suppressed in test/sanitize/*.supp (each one explained).
# Then the message fuzz targets (test/fuzz/run_fuzz.sh), FUZZ_SECONDS each (default 15), JOBS at
# a time; a longer search is `FUZZ_SECONDS=600 make test-sanitize` or `test/fuzz/run_fuzz.sh 600`.
# Last line: "sanitize: N passed, N failed, N skipped".
# Environment: SANITIZE_DIR (build folder, default <repo>/.ws/sanitize), JOBS (default: cores),
# SANITIZE_RESULTS (JUnit folder, default <build folder>/test_results).
set -eo pipefail

repo="$(cd "$(dirname "${BASH_SOURCE[0]}")/.." && pwd)"
build="${SANITIZE_DIR:-${repo}/.ws/sanitize}"
jobs="${JOBS:-$(nproc)}"
results="${SANITIZE_RESULTS:-${build}/test_results}"
supp="${repo}/test/sanitize"

start=$(date +%s)
mkdir -p "${build}"
if ! { cmake -S "${supp}" -B "${build}" -DCMAKE_BUILD_TYPE=Debug >"${build}/configure.log" 2>&1 &&
       cmake --build "${build}" -j "${jobs}" --target ebslam_tests dasp_tests edvs_tests; }; then
  tail -n 40 "${build}/configure.log"
  echo "test-sanitize: build failed"
  echo "sanitize: 0 passed, 1 failed"
  exit 1
fi
built=$(date +%s)

# halt_on_error: the first finding ends the test (it fails); detect_leaks: LeakSanitizer too.
export ASAN_OPTIONS="halt_on_error=1:detect_leaks=1:abort_on_error=0:strict_string_checks=1:detect_stack_use_after_return=1:check_initialization_order=1:suppressions=${supp}/asan.supp"
export LSAN_OPTIONS="suppressions=${supp}/lsan.supp:print_suppressions=0"
export UBSAN_OPTIONS="halt_on_error=1:print_stacktrace=1:suppressions=${supp}/ubsan.supp"

rm -rf "${results}"
mkdir -p "${results}"
status=0
(cd "${build}" && ctest --output-on-failure --timeout 600 -j "${jobs}" \
  --output-junit "${results}/sanitize-ctest.xml") >"${build}/ctest.log" 2>&1 || status=1
grep -E "tests passed|FAILED|Failed|ERROR: (Address|Leak)Sanitizer|runtime error" "${build}/ctest.log" | head -n 40 || true
tested=$(date +%s)
echo "test-sanitize: build $((built - start)) s, tests $((tested - built)) s (log: ${build}/ctest.log)"
# Every message a nodelet subscribes to, fuzzed through its conversion (test/fuzz, clang):
# FUZZ_SECONDS per target (default 15; 0 skips them). One JUnit case per target.
if [ "${FUZZ_SECONDS:-15}" != 0 ]; then
  FUZZ_BUILD="${build}/fuzz" FUZZ_RESULTS="${results}" JOBS="${jobs}" \
    bash "${repo}/test/fuzz/run_fuzz.sh" "${FUZZ_SECONDS:-15}" || status=1
  echo "test-sanitize: fuzzing $(( $(date +%s) - tested )) s"
fi
counts=$(/usr/bin/python3 "${repo}/scripts/count_junit.py" \
  --expected-skips "${repo}/test/expected_skips.txt" "${results}") || status=1
printf '%s\n' "${counts}" | sed '$d'
echo "sanitize: $(printf '%s\n' "${counts}" | tail -n 1)"
exit "${status}"
