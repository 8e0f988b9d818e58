#!/usr/bin/env bash
# make demo: the pipeline on the sample session, headless. Assumes `scripts/ws.sh build`.
#  0. ROS: the recorded floor-robot session through playback.launch (DASP, s-DASP, EB-SLAM-2D), and
#     the recorded D-eDVS session through playback.launch slam:=ebslam3d (depth fusion, EB-SLAM-3D):
#     its RMSE against the ground truth (and the offline core's on the same events) and a
#     screenshot of the 3D view (rviz under Xvfb) into demo_output/dedvs/.
#  1. Part II offline: simulate the eDVS on a floor robot under a ceiling along 12 s of a real robot
#     trajectory (thesis 6.5.3), localise with EB-PF on the known ceiling map and run EB-SLAM-2D,
#     and score both trajectories against the ground truth.
#  2. Part I offline: DASP superpixels of every sample RGB-D frame (labels, overlay, list).
#  3. ROS: an emulated eDVS on a pseudo-terminal streams the simulated events to the eDVS driver
#     nodelet while the RGB-D source plays the sample frames; rosbag records all topics. The
#     emulator starts once the recorder is connected to the driver's events, so the bag holds the
#     stream from its first event (the summary checks it).
# Outputs go to demo_output/; the summary is printed and written to demo_output/summary.txt.
set -eo pipefail
repo="$(cd "$(dirname "${BASH_SOURCE[0]}")/.." && pwd)"
ws="${WS_DIR:-${repo}/.ws}"
out="${repo}/demo_output"
session="${repo}/test/data/sample_session"
source "${repo}/scripts/ros_env.sh"
set +u
# shellcheck disable=SC1091
source "${ws}/devel/setup.bash"
rm -rf "${out}"
mkdir -p "${out}/events2d" "${out}/superpixels" "${out}/logs"
export PATH="${ws}/devel/bin:${PATH}"
summary="${out}/summary_offline.txt"
: >"${summary}"
note() { echo "$*" | tee -a "${summary}"; }

step() {  # step NAME LOG COMMAND...: runs a step, keeps its log, says how it went
  local name=$1 log=$2
  shift 2
  local start=${SECONDS}
  if "$@" >"${log}" 2>&1; then
    echo "demo: ${name} done in $((SECONDS - start)) s"
  else
    note "  ${name}: FAILED (see ${log#"${repo}"/})"
    return 1
  fi
}

# rviz under a virtual display (Mesa llvmpipe) for the launch that follows, and a capture of the
# screen every second while it runs; the last capture that shows rviz (not one flat colour: rviz not
# up yet, or closed) is kept as KEPT, so the picture is from near the end of the bag whatever the
# machine's speed. Sets rviz_arg (true when rviz can run), display, xvfb_pid and capture_pid.
#   start_rviz_capture DISPLAY_OFFSET XVFB_LOG KEPT SECONDS
start_rviz_capture() {
  rviz_arg=false
  xvfb_pid=""
  capture_pid=""
  capture_tmp=""
  display=""
  if ! { command -v Xvfb >/dev/null && command -v rviz >/dev/null && [ -x /usr/bin/import ]; }; then
    return 0
  fi
  display=":$((90 + (port + $1) % 9))"
  Xvfb "${display}" -screen 0 1280x800x24 +extension GLX >"${out}/logs/$2" 2>&1 &
  xvfb_pid=$!
  rviz_arg=true
  local kept="$3" seconds="$4"
  capture_tmp="${kept%.png}_capture.png"
  (for _ in $(seq 1 "${seconds}"); do
     sleep 1
     DISPLAY="${display}" /usr/bin/import -window root "${capture_tmp}" >/dev/null 2>&1 || continue
     if [ "$(/usr/bin/convert "${capture_tmp}" -format '%[fx:standard_deviation>0.02]' info: 2>/dev/null)" = 1 ]; then
       mv -f "${capture_tmp}" "${kept}"
     fi
   done) &
  capture_pid=$!
}

# Ends the capture loop of start_rviz_capture (the kept picture stays).
end_capture_loop() {
  [ -n "${capture_pid}" ] && kill "${capture_pid}" 2>/dev/null || true
  [ -n "${capture_tmp}" ] && rm -f "${capture_tmp}"
  return 0
}

# Ends the capture loop and the virtual display of start_rviz_capture.
stop_rviz_capture() {
  end_capture_loop
  [ -n "${xvfb_pid}" ] && kill "${xvfb_pid}" 2>/dev/null || true
  wait 2>/dev/null || true
}

status=0
echo "demo: 0. the recorded session through launch/playback.launch (DASP, s-DASP, EB-SLAM-2D, event image)"
# A master of our own on a free port, so the demo never talks to another running ROS system.
port=$(/usr/bin/python3 -c 'import socket; s=socket.socket(); s.bind(("localhost", 0)); print(s.getsockname()[1])')
export ROS_MASTER_URI="http://localhost:${port}"
export ROS_LOG_DIR="${out}/logs"
pb="${out}/playback"
mkdir -p "${pb}"
start_rviz_capture 0 xvfb.log "${pb}/rviz.png" 300
if DISPLAY="${display:-}" LIBGL_ALWAYS_SOFTWARE=1 roslaunch -p "${port}" "${repo}/launch/demo_playback.launch" \
  output_dir:="${pb}" rviz:="${rviz_arg}" </dev/null >"${out}/logs/playback_roslaunch.log" 2>&1 &&
  end_capture_loop &&
  /usr/bin/python3 "${repo}/scripts/demo_outputs.py" "${pb}/demo.bag" "${pb}" >"${pb}/topics_summary.txt"; then
  ebslam_evaluate_trajectory --no-time-offset "${pb}/trajectory.tum" "${pb}/ground_truth.tum" >"${pb}/trajectory_eval.txt" 2>&1 || status=1
  note "  playback of test/data/session/session.bag (outputs in demo_output/playback):"
  cat "${pb}/topics_summary.txt" | tee -a "${summary}"
  note "  EB-SLAM-2D through ROS (/ebslam/pose against /ground_truth/pose): $(grep -E 'position RMSE' "${pb}/trajectory_eval.txt" | tr -s ' ')"
  [ -f "${pb}/rviz.png" ] && note "  rviz screenshot: demo_output/playback/rviz.png"
else
  note "  playback: FAILED (see demo_output/logs/playback_roslaunch.log)"
  status=1
fi
stop_rviz_capture

echo "demo: 0b. the D-eDVS session through playback.launch slam:=ebslam3d (depth fusion, EB-SLAM-3D)"
d3="${out}/dedvs"
mkdir -p "${d3}"
session3d="${repo}/test/data/dedvs_session/dedvs_session.bag"
calibration3d="${repo}/ebslam_ros/config/dedvs_sensors.yaml"
start_rviz_capture 1 xvfb3d.log "${d3}/rviz_ebslam3d.png" 120
start3d=${SECONDS}
if DISPLAY="${display:-}" LIBGL_ALWAYS_SOFTWARE=1 roslaunch -p "${port}" "${repo}/launch/demo_playback3d.launch" \
  output_dir:="${d3}" rviz:="${rviz_arg}" </dev/null >"${out}/logs/playback3d_roslaunch.log" 2>&1; then
  end_capture_loop
  if rosrun ebslam_ros dedvs_session_eval --session "${session3d}" --calibration "${calibration3d}" --poses "${d3}/demo3d.bag" \
    --estimate "${d3}/trajectory.tum" >"${d3}/rmse.txt" 2>&1; then
    note "  D-eDVS session test/data/dedvs_session/dedvs_session.bag through ROS in $((SECONDS - start3d)) s (outputs in demo_output/dedvs):"
    note "    EB-SLAM-3D through ROS against the ground truth: $(sed -n 's/^published //p' "${d3}/rmse.txt")"
    note "    the offline core on the same events: $(sed -n 's/^offline core: //p' "${d3}/rmse.txt")"
  else
    note "  D-eDVS session: scoring FAILED (see demo_output/dedvs/rmse.txt)"
    status=1
  fi
  [ -f "${d3}/rviz_ebslam3d.png" ] && note "    rviz screenshot of the 3D view: demo_output/dedvs/rviz_ebslam3d.png"
else
  note "  D-eDVS playback: FAILED (see demo_output/logs/playback3d_roslaunch.log)"
  status=1
fi
stop_rviz_capture

echo "demo: 1. event simulation, EB-PF and EB-SLAM-2D"
e2d="${out}/events2d"
# G0 as in docs/results/events2d.md (the thesis' 250 diffuses too little on this ceiling); the
# simulator shares the ground-truth clock, so trajectories are scored without a time offset.
ebpf_g0=60
ebslam_g0=30
if step "event simulation" "${e2d}/simulate.log" ebslam_simulate_events \
  --trajectory "${session}/pioneer_360_excerpt.txt" --seed 1 \
  --events "${e2d}/events.bin" --groundtruth "${e2d}/groundtruth.txt" --map "${e2d}/ceiling"; then
  note "  simulation: $(grep -E '^events:' "${e2d}/simulate.log" | head -1)"
  origin_x=$(sed -n 's/^origin_x_m: *//p' "${e2d}/ceiling.yaml")
  origin_y=$(sed -n 's/^origin_y_m: *//p' "${e2d}/ceiling.yaml")
  if step "EB-PF" "${e2d}/ebpf.log" ebslam_run_ebpf "${e2d}/events.bin" --edges "${e2d}/ceiling_edges.png" \
    --map-origin "${origin_x}" "${origin_y}" --start-from "${e2d}/groundtruth.txt" --g0 "${ebpf_g0}" \
    -o "${e2d}/ebpf.txt"; then
    ebslam_evaluate_trajectory --no-time-offset "${e2d}/ebpf.txt" "${e2d}/groundtruth.txt" >"${e2d}/ebpf_eval.txt" 2>&1 || status=1
    note "  EB-PF (known ceiling map): $(grep -E 'position RMSE' "${e2d}/ebpf_eval.txt" | head -1 | tr -s ' '), $(grep -iE 'events/s|events per second' "${e2d}/ebpf.log" | tail -1 | tr -s ' ')"
  else status=1; fi
  if step "EB-SLAM-2D" "${e2d}/ebslam2d.log" ebslam_run_ebslam2d "${e2d}/events.bin" \
    --start-from "${e2d}/groundtruth.txt" --g0 "${ebslam_g0}" -o "${e2d}/ebslam2d.txt" \
    --map-png "${e2d}/ebslam2d_map.png"; then
    ebslam_evaluate_trajectory --no-time-offset "${e2d}/ebslam2d.txt" "${e2d}/groundtruth.txt" >"${e2d}/ebslam2d_eval.txt" 2>&1 || status=1
    note "  EB-SLAM-2D: $(grep -E 'position RMSE' "${e2d}/ebslam2d_eval.txt" | head -1 | tr -s ' '), $(grep -iE 'events/s|events per second' "${e2d}/ebslam2d.log" | tail -1 | tr -s ' ')"
  else status=1; fi
else
  status=1
fi

echo "demo: 2. DASP superpixels of the sample frames"
frames=0
for rgb in "${session}"/sample*_rgb.png; do
  name=$(basename "${rgb}" _rgb.png)
  sp="${out}/superpixels/${name}"
  if step "DASP ${name}" "${sp}.log" dasp_segment --color "${rgb}" --depth "${session}/${name}_depth_mm.png" \
    --labels "${sp}_labels.png" --overlay "${sp}_overlay.png" --list "${sp}_superpixels.csv"; then
    frames=$((frames + 1))
  else status=1; fi
done
note "  DASP: ${frames} frames segmented into demo_output/superpixels; first: $(head -n1 "${out}"/superpixels/sample0.log 2>/dev/null)"

echo "demo: 3. ROS pipeline (emulated eDVS -> driver nodelet, RGB-D source -> rosbag)"
# A master of our own on a free port, so the demo never talks to another running ROS system.
port=$(/usr/bin/python3 -c 'import socket; s=socket.socket(); s.bind(("localhost", 0)); print(s.getsockname()[1])')
export ROS_MASTER_URI="http://localhost:${port}"
export ROS_LOG_DIR="${out}/logs"
link="/tmp/edvs_demo_$$"
events_file="${e2d}/events.bin"
[ -f "${events_file}" ] || events_file="${repo}/ebslam_ros/test/data/events.txt"
# The launch starts the recorder, the RGB-D source (it waits for its subscribers) and the driver,
# which retries opening the link until the emulator has made it. The emulator starts streaming
# when the driver opens it, so it starts only once the recorder is connected to edvs/events.
roslaunch -p "${port}" "${repo}/launch/demo.launch" output_dir:="${out}" \
  edvs_uri:="serial://${link}?format=E2" </dev/null >"${out}/roslaunch.log" 2>&1 &
launch_pid=$!
emulator_pid=""
trap 'kill ${launch_pid} ${emulator_pid} 2>/dev/null || true' EXIT
if /usr/bin/python3 "${repo}/scripts/wait_for_connection.py" /recorder /edvs/events 60; then
  rosrun edvs_driver edvs_emulator --link "${link}" --file "${events_file}" --baud 4000000 --duration 60 >"${out}/logs/emulator.log" 2>&1 &
  emulator_pid=$!
else
  status=1
fi
if wait "${launch_pid}"; then
  ebslam_event_convert "${events_file}" "${out}/logs/emulated_events.txt" --to text >/dev/null 2>&1 || true
  /usr/bin/python3 "${repo}/scripts/demo_summary.py" "${out}" "${out}/logs/emulated_events.txt" \
    >"${out}/summary_ros.txt" || status=1
else
  echo "demo: roslaunch failed, see demo_output/roslaunch.log" >&2
  tail -n 20 "${out}/roslaunch.log" >&2
  status=1
fi
[ -n "${emulator_pid}" ] && kill "${emulator_pid}" 2>/dev/null || true

{
  echo "demo summary (outputs in demo_output/)"
  cat "${summary}"
  [ -f "${out}/summary_ros.txt" ] && cat "${out}/summary_ros.txt"
  echo "  result: $([ ${status} -eq 0 ] && echo OK || echo 'PROBLEMS (see above)')"
} | tee "${out}/summary.txt"
exit ${status}
