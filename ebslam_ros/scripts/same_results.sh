#!/usr/bin/env bash
# "Same results through ROS" check: the simulator nodelet -> EventSlam2d / EventParticleFilter in one
# manager on /clock at SPEED x real time, recorded, converted with bag_to_tum and scored with
# ebslam_evaluate_trajectory, beside the offline ebslam_run_ebslam2d / ebslam_run_ebpf on the same
# events (ebslam_simulate_events with the same trajectory, scene and seed): once recording a pose
# every 100 events (the tools' default) and once per 10 ms window of event time, as the nodes
# receive the simulator's 100 Hz messages and publish a pose per message. Both are scored at their
# own instants; the ROS run is compared with the second (the same instants), also pose by pose.
#   ebslam_ros/scripts/same_results.sh TUM_TRAJECTORY OUT_DIR [SPEED] [SEED]
set -eo pipefail
repo="$(cd "$(dirname "${BASH_SOURCE[0]}")/../.." && pwd)"
trajectory=${1:?TUM trajectory}
out=${2:?output folder}
speed=${3:-10}
seed=${4:-1}
source "${repo}/scripts/ros_env.sh"
set +u
source "${WS_DIR:-${repo}/.ws}/devel/setup.bash"
export ROS_HOSTNAME=localhost
bin="${WS_DIR:-${repo}/.ws}/build/ebslam"
mkdir -p "${out}"
cd "${out}"

if [ ! -f events.ebe ]; then
  "${bin}/ebslam_simulate_events" --trajectory "${trajectory}" --seed "${seed}" --events events.ebe \
    --groundtruth groundtruth.tum --map ceiling >simulate.log
fi
grep '^events:' simulate.log
# The start pose, given to the offline tools and the nodes with the same digits (EB-SLAM-2D is
# chaotic: a start differing by 1e-10 m gives another, equally good trajectory).
start=$(/usr/bin/python3 -c "
import math
for line in open('groundtruth.tum'):
    if line.startswith('#'): continue
    t, x, y, z, qx, qy, qz, qw = map(float, line.split())
    print('%.9f %.9f %.9f' % (x, y, 2 * math.atan2(qz, qw))); break")
ox=$(sed -n 's/^origin_x_m: *//p' ceiling.yaml)
oy=$(sed -n 's/^origin_y_m: *//p' ceiling.yaml)
"${bin}/ebslam_run_ebslam2d" events.ebe --start ${start} --g0 30 -o slam_offline.tum | tail -1
"${bin}/ebslam_run_ebpf" events.ebe --edges ceiling_edges.png --map-origin "${ox}" "${oy}" \
  --start ${start} --g0 60 -o ebpf_offline.tum | tail -1
"${bin}/ebslam_run_ebslam2d" events.ebe --start ${start} --g0 30 --message-us 10000 \
  -o slam_offline_messages.tum | tail -1
"${bin}/ebslam_run_ebpf" events.ebe --edges ceiling_edges.png --map-origin "${ox}" "${oy}" \
  --start ${start} --g0 60 --message-us 10000 -o ebpf_offline_messages.tum | tail -1

port=$(/usr/bin/python3 -c 'import socket; s=socket.socket(); s.bind(("",0)); print(s.getsockname()[1])')
export ROS_MASTER_URI=http://localhost:${port}
for filter in ${FILTERS:-slam ebpf}; do
  rm -f "${filter}.bag" "${filter}_launch.log"
  roslaunch -p "${port}" ebslam_ros simulated_localisation.launch filter:="${filter}" speed:="${speed}" \
    seed:="${seed}" trajectory:="${trajectory}" initial_pose:="[${start// /, }]" map:="${out}/ceiling.yaml" \
    bag:="${out}/${filter}.bag" >"${filter}_launch.log" 2>&1 &
  launch=$!
  start_wall=${SECONDS}
  until grep -q "simulation done" "${filter}_launch.log" 2>/dev/null; do
    sleep 1
    if ! kill -0 "${launch}" 2>/dev/null; then echo "roslaunch ended early: ${filter}_launch.log"; exit 1; fi
  done
  echo "${filter}: simulation done after $((SECONDS - start_wall)) s wall"
  sleep 20  # the filter drains its queue, rosbag writes
  kill -INT "${launch}"
  wait "${launch}" || true
  rosrun ebslam_ros bag_to_tum "${filter}.bag" /pose "${filter}_ros.tum"
  rosrun ebslam_ros bag_to_tum "${filter}.bag" /ground_truth/pose "${filter}_ros_groundtruth.tum"
done
for filter in ${FILTERS:-slam ebpf}; do
  echo "== ${filter} offline, a pose every 100 events:"
  "${bin}/ebslam_evaluate_trajectory" --no-time-offset "${filter}_offline.tum" groundtruth.tum | grep RMSE
  echo "== ${filter} offline, a pose per 10 ms message:"
  "${bin}/ebslam_evaluate_trajectory" --no-time-offset "${filter}_offline_messages.tum" groundtruth.tum | grep RMSE
  echo "== ${filter} through ROS (${speed}x, /clock):"
  "${bin}/ebslam_evaluate_trajectory" --no-time-offset "${filter}_ros.tum" "${filter}_ros_groundtruth.tum" | grep RMSE
done
# Pose by pose: ROS stamps are clock_start (1000 s) + event time.
for filter in ${FILTERS:-slam ebpf}; do
  /usr/bin/python3 "${repo}/ebslam_ros/scripts/compare_trajectories.py" "${filter}_ros.tum" 1000 \
    "${filter}_offline_messages.tum"
done
