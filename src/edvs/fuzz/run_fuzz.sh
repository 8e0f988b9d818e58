#!/usr/bin/env bash
# Builds the libFuzzer targets with clang (ASan + UBSan) in a build directory outside the repo and
# runs each for a while, merging new interesting inputs into the small corpus kept in the repo.
#   src/edvs/fuzz/run_fuzz.sh [seconds per target (default 180)] [build dir (default /tmp/edvs_fuzz)]
set -euo pipefail
here="$(cd "$(dirname "${BASH_SOURCE[0]}")" && pwd)"
lib="$(dirname "${here}")"
src="$(dirname "${lib}")"
seconds="${1:-180}"
build="${2:-/tmp/edvs_fuzz}"
mkdir -p "${build}"
flags=(-std=c++17 -O1 -g -fsanitize=fuzzer,address,undefined -fno-sanitize-recover=undefined
  -I"${lib}/include" -I"${src}/ebslam/include")
sources=()
for name in biases commands event_encoder event_format event_framing event_parser format_detection \
  timestamp_unwrapper device transport serial_baud usb_discovery; do
  sources+=("${lib}/src/${name}.cpp")
done
for target in parser_fuzzer uri_fuzzer; do
  clang++ "${flags[@]}" "${here}/${target}.cpp" "${sources[@]}" -lusb-1.0 -lpthread \
    -o "${build}/${target}"
done
for target in parser_fuzzer uri_fuzzer; do
  corpus="${here}/corpus/${target%_fuzzer}"
  work="${build}/${target}_corpus"
  mkdir -p "${work}"
  cp -n "${corpus}"/* "${work}/" 2>/dev/null || true
  echo "== ${target}: ${seconds} s"
  "${build}/${target}" -max_total_time="${seconds}" -max_len=512 -print_final_stats=1 \
    "${work}" 2>&1 | grep -E "^(#|stat::|==|SUMMARY|Done)" | tail -8
  # Keep the repository corpus small: only inputs that add coverage, up to 64 of them.
  tmp="$(mktemp -d)"
  "${build}/${target}" -merge=1 "${tmp}" "${corpus}" "${work}" >/dev/null 2>&1 || true
  if [ "$(ls "${tmp}" | wc -l)" -le 64 ]; then
    rm -f "${corpus}"/*
    cp "${tmp}"/* "${corpus}/"
  fi
  rm -rf "${tmp}"
  echo "   corpus: $(ls "${corpus}" | wc -l) files, $(du -sk "${corpus}" | cut -f1) KiB"
done
