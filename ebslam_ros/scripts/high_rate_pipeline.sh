#!/usr/bin/env bash
# A megapixel event camera through the ROS pipeline (not a test; machines are shared): a
# deterministic 1280x720 evt3 source (high_rate_source) at RATE events/s for DURATION s feeds
# EventDenoiser and EventRenderer, the denoised events feed EventSlam2d, all three nodelets in
# one manager as in the launch files; prints high_rate_source's lines: pose latency, messages
# sent against received per node (queues never full when equal), input/processed rates and the
# rate cap's dropped share from each node's /diagnostics.
#   ebslam_ros/scripts/high_rate_pipeline.sh [RATE] [DURATION] [MAX_EVENT_RATE] [ENCODING]
# (defaults 10000000 20 (the node's default cap: empty) evt3). Needs the built workspace (.ws);
# starts its own ROS master on a free port.
set -eo pipefail
rate=${1:-10000000}
duration=${2:-20}
cap=${3:-}
encoding=${4:-evt3}
source "$(dirname "${BASH_SOURCE[0]}")/private_master.sh"
pids=()
trap 'for p in "${pids[@]}"; do kill "${p}" 2>/dev/null || true; done; kill ${ros_master_pid} 2>/dev/null || true' EXIT

# The camera of the source: 1280x720, f = 800 px, 2.59 m under the ceiling (3.2 mm per pixel);
# map cells of 4 pixels (1.3 cm) over 12 m.
rosparam set /slam/camera/width 1280
rosparam set /slam/camera/height 720
rosparam set /slam/camera/focal_px 800.0
rosparam set /slam/camera/cx 639.5
rosparam set /slam/camera/cy 359.5
rosparam set /slam/cell_size 4.0
rosparam set /slam/map_size 12.0
rosparam set /slam/queue_size 1000
if [ -n "${cap}" ]; then rosparam set /slam/max_event_rate "${cap}"; fi
rosparam set /denoiser/input_type event_packet
rosparam set /renderer/input_type event_packet
rosparam set /denoiser/window 0.01
rosparam set /denoiser/min_support 2
rosparam set /renderer/accumulation_time 0.01

rosrun nodelet nodelet manager __name:=manager >/tmp/high_rate_manager.log 2>&1 &
pids+=($!)
sleep 1
rosrun nodelet nodelet load ebslam_ros/EventDenoiser manager __name:=denoiser >/dev/null 2>&1 &
pids+=($!)
rosrun nodelet nodelet load ebslam_ros/EventRenderer manager __name:=renderer >/dev/null 2>&1 &
pids+=($!)
rosrun nodelet nodelet load ebslam_ros/EventSlam2d manager __name:=slam events:=events_denoised \
  >/dev/null 2>&1 &
pids+=($!)
sleep 2
rosrun ebslam_ros high_rate_source --rate "${rate}" --duration "${duration}" --encoding "${encoding}"
