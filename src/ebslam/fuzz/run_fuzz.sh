#!/usr/bin/env bash
# Builds and runs the libFuzzer targets for the event file and TUM trajectory readers, the
# event packet decoders (one target per encoding) and the event packet file reader.
# Not part of the normal build: compiles the reader sources directly with clang++.
#
#   src/ebslam/fuzz/run_fuzz.sh [seconds per target, default 180] [target ...]
#
# Needs clang and libclang-rt-14-dev (scripts/install_deps.sh installs both). Builds and the
# working corpus go to ${FUZZ_WORK:-/tmp/ebslam_fuzz}; the small seed corpus in corpus/<target>
# stays unchanged. Crashes are written as ${FUZZ_WORK}/<target>/crash-*; the script exits
# non-zero when a target fails.
set -euo pipefail

here="$(cd "$(dirname "${BASH_SOURCE[0]}")" && pwd)"
lib="$(dirname "${here}")"
seconds="${1:-180}"
shift || true
targets=("$@")
if [ ${#targets[@]} -eq 0 ]; then
  targets=(fuzz_event_reader fuzz_tum_reader fuzz_evt3_decoder fuzz_libcaer_decoder
           fuzz_libcaer_cmp_decoder fuzz_mono_decoder fuzz_event_packet_file)
fi
work="${FUZZ_WORK:-/tmp/ebslam_fuzz}"
cxx="${CXX_FUZZ:-clang++}"
flags=(-std=c++17 -g -O1 -fno-omit-frame-pointer -fsanitize=fuzzer,address,undefined
       -fno-sanitize-recover=undefined -I"${lib}/include" -isystem /usr/include/eigen3)

declare -A sources=(
  [fuzz_event_reader]="${lib}/src/events/event_io.cpp ${lib}/src/events/event_file_writer.cpp"
  [fuzz_tum_reader]="${lib}/src/events/trajectory.cpp"
  [fuzz_evt3_decoder]="${lib}/src/events/event_packet.cpp"
  [fuzz_libcaer_decoder]="${lib}/src/events/event_packet.cpp"
  [fuzz_libcaer_cmp_decoder]="${lib}/src/events/event_packet.cpp"
  [fuzz_mono_decoder]="${lib}/src/events/event_packet.cpp"
  [fuzz_event_packet_file]="${lib}/src/events/event_packet.cpp"
)

status=0
for target in "${targets[@]}"; do
  if [ -z "${sources[${target}]:-}" ]; then
    echo "run_fuzz: unknown target ${target}" >&2
    exit 1
  fi
  out="${work}/${target}"
  mkdir -p "${out}/corpus"
  echo "run_fuzz: building ${target}"
  "${cxx}" "${flags[@]}" "${here}/${target}.cpp" ${sources[${target}]} -o "${out}/${target}"
  cp -n "${here}/corpus/${target}/"* "${out}/corpus/" 2>/dev/null || true
  echo "run_fuzz: running ${target} for ${seconds} s"
  if ! (cd "${out}" && "./${target}" -max_total_time="${seconds}" -max_len=8192 -timeout=10 \
          -rss_limit_mb=2048 -print_final_stats=1 -artifact_prefix="${out}/" corpus); then
    echo "run_fuzz: ${target} FAILED, see ${out}/crash-* or leak-*/timeout-*" >&2
    status=1
  fi
done
exit "${status}"
