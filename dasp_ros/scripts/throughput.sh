#!/usr/bin/env bash
# Throughput of dasp_ros (a measurement, not a test): RgbdFolderSource at 30 Hz, 640x480,
# loops over a folder (default: the OSD learn frames):
#   source   the source alone in the manager (its CPU per frame, subtracted below)
#   pipeline Dasp + Sdasp in the same manager, DASP single-threaded: rate, frames without output, CPU
#   lazy     the same with subscribers to every lazy output
#   tdasp    Tdasp alone at 30 Hz input, the manager pinned to one core (taskset -c 1)
#   core     the core library on the same frames in one thread (core_pipeline_cpu)
# Usage: dasp_ros/scripts/throughput.sh [folder] [seconds]   (after `make build`)
set -eo pipefail
repo="$(cd "$(dirname "${BASH_SOURCE[0]}")/../.." && pwd)"
# ../shared beside this checkout, or beside the main checkout when this is a git worktree.
main_repo="$(dirname "$(git -C "${repo}" rev-parse --path-format=absolute --git-common-dir 2>/dev/null || echo "${repo}/.git")")"
default_folder="${repo}/../shared/data/osd/learn"
[ -d "${default_folder}" ] || default_folder="${main_repo}/../shared/data/osd/learn"
folder="${1:-${default_folder}}"
seconds="${2:-60}"
source "${repo}/scripts/ros_env.sh"
set +u; source "${repo}/.ws/devel/setup.bash"; set -u
core="$(find "${repo}/.ws/devel" "${repo}/.ws/build" -type f -name core_pipeline_cpu -perm -u+x | head -n1)"
measure="${repo}/dasp_ros/scripts/throughput.py"

run() {  # name, output topic, extra measure arg, launch args...
  local name="$1" topic="$2" extra="$3"; shift 3
  local port; port=$(/usr/bin/python3 -c 'import socket; s=socket.socket(); s.bind(("localhost", 0)); print(s.getsockname()[1])')
  export ROS_MASTER_URI="http://localhost:${port}"
  ${PREFIX:-} roslaunch -p "${port}" dasp_ros folder_segmentation.launch folder:="${folder}" rate:=30 \
    loop:=true wait_for_subscribers:=false "$@" >"/tmp/dasp_ros_throughput_${name}.log" 2>&1 &
  local pid=$!
  sleep 4
  echo "${name}: $(/usr/bin/python3 "${measure}" "${topic}" "${seconds}" ${extra})"
  kill -INT "${pid}"; wait "${pid}" || true
}

echo "load before: $(cut -d' ' -f1-3 /proc/loadavg)"
run source /camera/segmentation "" dasp:=false sdasp:=false
run pipeline /camera/segmentation ""
run lazy /camera/segmentation lazy
PREFIX="taskset -c 1" run tdasp /camera/tdasp/segmentation "" dasp:=false sdasp:=false tdasp:=true
echo "core: $("${core}" "${folder}" 2)"
echo "core: $("${core}" "${folder}" 1 tdasp)"
echo "load after: $(cut -d' ' -f1-3 /proc/loadavg)"
