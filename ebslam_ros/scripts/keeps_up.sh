#!/usr/bin/env bash
# Whether EventSlam2d keeps up: events at 200k and 600k events/s in 100 Hz messages for DURATION s
# each (default 60), N = 25, against a fresh nodelet each; prints keeps_up_bench's lines.
#   ebslam_ros/scripts/keeps_up.sh EVENTS_FILE [DURATION] [N]
# Needs the built workspace (.ws) and its own ROS master (started here on a free port).
set -eo pipefail
events=${1:?event file}
duration=${2:-60}
particles=${3:-25}
source "$(dirname "${BASH_SOURCE[0]}")/private_master.sh"
trap 'kill ${filter} ${ros_master_pid} 2>/dev/null || true' EXIT
for rate in 200000 600000; do
  rosrun ebslam_ros event_slam2d_node _num_particles:="${particles}" _queue_size:=100000 \
    __name:=slam >/dev/null 2>&1 &
  filter=$!
  sleep 2
  rosrun ebslam_ros keeps_up_bench --events "${events}" --rate "${rate}" --duration "${duration}" \
    -N "${particles}"
  kill "${filter}"
  wait "${filter}" 2>/dev/null || true
done
