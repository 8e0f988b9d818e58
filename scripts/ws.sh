#!/usr/bin/env bash
# Builds and tests the catkin workspace whose source space is this repository.
#   scripts/ws.sh build   catkin build of every package (and its tests) into .ws/
#   scripts/ws.sh test    build, then run every gtest/ctest/rostest; last line "N passed, N failed, N skipped"
# Environment: WS_DIR (default <repo>/.ws), JOBS (default: number of cores), DEBUG_INFO_FLAGS
# (default -g1).
set -eo pipefail

repo="$(cd "$(dirname "${BASH_SOURCE[0]}")/.." && pwd)"
ws="${WS_DIR:-${repo}/.ws}"
jobs="${JOBS:-$(nproc)}"
# shellcheck source=ros_env.sh
source "${repo}/scripts/ros_env.sh"

# -O2 as CMake's RelWithDebInfo, with line tables only (-g1): backtraces name file and line, the
# code is the same, and the build takes about a fifth less time than with full -g (5x smaller
# objects). DEBUG_INFO_FLAGS=-g gives full debug info.
RELWITHDEBINFO_FLAGS="-O2 ${DEBUG_INFO_FLAGS:--g1} -DNDEBUG"

configure() {
  mkdir -p "${ws}"
  # The workspace lives inside the source space: keep catkin from crawling it for packages.
  touch "${ws}/CATKIN_IGNORE"
  if [ ! -d "${ws}/.catkin_tools" ]; then
    (cd "${ws}" && catkin init >/dev/null)
  fi
  (cd "${ws}" && catkin config --source-space "${repo}" \
    --cmake-args -DCMAKE_BUILD_TYPE=RelWithDebInfo -DCMAKE_EXPORT_COMPILE_COMMANDS=ON \
    "-DCMAKE_CXX_FLAGS_RELWITHDEBINFO=${RELWITHDEBINFO_FLAGS}" \
    "-DCMAKE_C_FLAGS_RELWITHDEBINFO=${RELWITHDEBINFO_FLAGS}" \
    -DPYTHON_EXECUTABLE=/usr/bin/python3 -DPython3_EXECUTABLE=/usr/bin/python3 \
    -DCATKIN_ENABLE_TESTING=ON -DBUILD_TESTING=ON >/dev/null)
}

build() {
  configure
  cd "${ws}"
  # Explicit statuses: `set -e` does not apply inside a function called as an `if` condition.
  local status=0
  catkin build -j "${jobs}" --no-status --no-notify --continue-on-failure --summarize || status=1
  # catkin packages build their gtest/rostest executables only in the `tests` target.
  catkin build -j "${jobs}" --no-status --no-notify --continue-on-failure --catkin-make-args tests || status=1
  # One compile_commands.json for clang-tidy and editors.
  /usr/bin/python3 "${repo}/scripts/merge_compile_commands.py" "${ws}/build" "${repo}/compile_commands.json" || status=1
  return "${status}"
}

package_build_type() {
  if grep -q '<build_type>cmake</build_type>' "$1/package.xml"; then echo cmake; else echo catkin; fi
}

# A step that failed must show as a failure in the summary even when it left no JUnit file that
# says so (a test binary that crashed while ctest listed it, a make error, catkin_test_results
# finding a missing result): then a synthetic failed case <label> is written into the results.
record_failure() {
  local label="$1" message="$2" checked="$3"
  if [ -e "${checked}" ] &&
     ! /usr/bin/python3 "${repo}/scripts/count_junit.py" "${checked}" 2>/dev/null | tail -n 1 |
       grep -q ' 0 failed'; then
    return 0  # the failure is in the results already
  fi
  message=$(printf '%s' "${message}" | tr -d '\000-\010' | sed 's/&/\&amp;/g; s/</\&lt;/g; s/>/\&gt;/g; s/"/\&quot;/g')
  printf '<?xml version="1.0"?><testsuite name="%s" tests="1" failures="1"><testcase classname="ws" name="%s"><failure message="%s"/></testcase></testsuite>\n' \
    "${label}" "${label}" "${message}" >"${results}/${label}-run-failure.xml"
}

run_tests() {
  cd "${ws}"
  # shellcheck disable=SC1091
  set +u; source "${ws}/devel/setup.bash"; set -u
  local results="${ws}/test_results"
  rm -rf "${results}"
  mkdir -p "${results}"
  local status=0
  local packages=()
  mapfile -t packages < <(find "${repo}" -name package.xml -not -path "${ws}/*" | sort | while read -r xml; do
                            dir=$(dirname "${xml}")
                            [ -e "${dir}/CATKIN_IGNORE" ] && continue
                            echo "$(sed -n 's:.*<name>\(.*\)</name>.*:\1:p' "${xml}" | head -n1) ${dir#"${repo}"/}"
                          done)
  # Checks of the workspace as a whole: package.xml completeness (scripts/check_package_deps.py).
  echo "=== workspace checks"
  /usr/bin/python3 "${repo}/scripts/tests/workspace_checks.py" "${results}/workspace_checks.xml" \
    </dev/null 2>&1 | tail -n 3 || status=1
  # Names written in the docs, launch-argument docs and yaml comments exist (headers, messages,
  # services, nodelets), and the package tables list every message and service.
  echo "=== docs references"
  /usr/bin/python3 "${repo}/scripts/tests/docs_references_test.py" "${results}/docs_references.xml" \
    </dev/null 2>&1 | tail -n 3 || status=1
  local entry name path
  for entry in "${packages[@]}"; do
    read -r name path <<<"${entry}"
    local build_dir="${ws}/build/${name}"
    [ -d "${build_dir}" ] || { echo "ws: no build folder for ${name}" >&2; status=1; continue; }
    echo "=== tests of ${name}"
    if [ "$(package_build_type "${repo}/${path}")" = cmake ]; then
      # Plain CMake package: its gtest cases are ctest tests; ctest writes JUnit.
      if [ -f "${build_dir}/CTestTestfile.cmake" ]; then
        # Tests read no standard input (rosbag play would take the package list below as key presses).
        local ctest_status=0
        (cd "${build_dir}" && ctest --output-on-failure --timeout 600 -j "${jobs}" </dev/null \
          --output-junit "${results}/${name}-ctest.xml") >"${results}/${name}-ctest.log" 2>&1 ||
          ctest_status=$?
        tail -n 25 "${results}/${name}-ctest.log"
        if [ "${ctest_status}" -ne 0 ]; then
          status=1
          record_failure "${name}-ctest" "ctest exited with status ${ctest_status}: $(grep -m3 -E 'Error|error|\*\*\*|Failed' "${results}/${name}-ctest.log" | tr '\n' ' ')" \
            "${results}/${name}-ctest.xml"
        fi
      else
        echo "ws: ${name} has no CTestTestfile.cmake: its tests were not configured" >&2
        status=1
      fi
    else
      # catkin package: run_tests writes gtest/rostest XML (a crashed test gets a MISSING-result failure).
      # Its tests run ${jobs} at a time: each rostest starts its own master on a free port
      # (rostest_parent.py: Master(port=0)) and writes its own result file.
      local make_status=0
      make -C "${build_dir}" -j "${jobs}" run_tests </dev/null >"${results}/${name}-run_tests.log" 2>&1 ||
        make_status=$?
      tail -n 40 "${results}/${name}-run_tests.log" | grep -E '^\[ *(OK|FAILED|PASSED|RUN) *\]|FAILURE|ERROR|SUMMARY|Ran ' || true
      if [ -d "${build_dir}/test_results/${name}" ]; then
        mkdir -p "${results}/${name}"
        cp "${build_dir}/test_results/${name}"/*.xml "${results}/${name}/" 2>/dev/null || true
      fi
      if [ "${make_status}" -ne 0 ]; then
        status=1
        record_failure "${name}-run_tests" "make run_tests exited with status ${make_status} (log ${results}/${name}-run_tests.log)" \
          "${results}/${name}"
      fi
    fi
  done
  # The install space on its own: installed into a temporary prefix (no rebuild), every launch file
  # started from there for a few seconds with its main topics asserted.
  echo "=== install space"
  /usr/bin/python3 "${repo}/scripts/tests/install_space_test.py" "${ws}" "${results}/install_space.xml" \
    </dev/null 2>&1 | tail -n 20 || status=1
  # The layering of the built libraries: the eDVS core, messages, driver and DASP nodes link no
  # SLAM, simulation or calibration code and no Ceres.
  echo "=== link layering"
  /usr/bin/python3 "${repo}/scripts/tests/link_layering_test.py" "${ws}" "${results}/link_layering.xml" \
    </dev/null 2>&1 | tail -n 3 || status=1
  # catkin_test_results checks catkin's own XML (and finds missing results); our counter reads
  # every file once (no double counting). Its failures are shown and counted, never discarded.
  local catkin_results
  if ! catkin_results=$(catkin_test_results "${results}" 2>&1); then
    status=1
    printf '%s\n' "${catkin_results}" | grep -vE '^(Summary|$)' | grep -iE 'fail|error|missing' | head -n 20 || true
    record_failure catkin_test_results "catkin_test_results: $(printf '%s' "${catkin_results}" | tail -n 1)" "${results}"
  fi
  # Every skip is named; one that test/expected_skips.txt does not list fails the run.
  /usr/bin/python3 "${repo}/scripts/count_junit.py" --expected-skips "${repo}/test/expected_skips.txt" \
    "${results}" || status=1
  return "${status}"
}

case "${1:-}" in
  build) build ;;
  test)
    if ! build; then
      echo "ws: build failed"
      echo "0 passed, 1 failed"
      exit 1
    fi
    run_tests
    ;;
  configure) configure ;;
  *) echo "usage: $0 build|test|configure" >&2; exit 2 ;;
esac
