#!/usr/bin/env bash
# Same results through ROS over a whole folder (default: the 45 OSD learn frames):
# dasp_segment and dasp_sdasp write label PNGs per frame, then the frames are played through
# RgbdFolderSource -> Dasp -> Sdasp and same_results.py compares the published labels.
# Usage: dasp_ros/scripts/same_results.sh [folder] [out_dir]   (after `make build`)
set -eo pipefail
repo="$(cd "$(dirname "${BASH_SOURCE[0]}")/../.." && pwd)"
# ../shared beside this checkout, or beside the main checkout when this is a git worktree.
main_repo="$(dirname "$(git -C "${repo}" rev-parse --path-format=absolute --git-common-dir 2>/dev/null || echo "${repo}/.git")")"
default_folder="${repo}/../shared/data/osd/learn"
[ -d "${default_folder}" ] || default_folder="${main_repo}/../shared/data/osd/learn"
folder="${1:-${default_folder}}"
out="${2:-/tmp/dasp_ros_same_results}"
[ -d "${folder}" ] || { echo "same_results: no folder ${folder} (../shared absent?)" >&2; exit 2; }
mkdir -p "${out}"
source "${repo}/scripts/ros_env.sh"
set +u; source "${repo}/.ws/devel/setup.bash"; set -u
segment="$(find "${repo}/.ws" -type f -name dasp_segment -perm -u+x | head -n1)"
sdasp="$(find "${repo}/.ws" -type f -name dasp_sdasp -perm -u+x | head -n1)"
[ -x "${segment}" ] && [ -x "${sdasp}" ] || { echo "same_results: build dasp's tools first" >&2; exit 2; }
for rgb in "${folder}"/*_rgb.png; do
  name="$(basename "${rgb}" _rgb.png)"
  depth="${folder}/${name}_depth_mm.png"
  [ -f "${depth}" ] || continue
  "${segment}" --color "${rgb}" --depth "${depth}" --labels "${out}/${name}_superpixels.png" >/dev/null
  "${sdasp}" segment --color "${rgb}" --depth "${depth}" --labels "${out}/${name}_segments.png" >/dev/null
done
port=$(/usr/bin/python3 -c 'import socket; s=socket.socket(); s.bind(("localhost", 0)); print(s.getsockname()[1])')
export ROS_MASTER_URI="http://localhost:${port}"
roslaunch -p "${port}" dasp_ros folder_segmentation.launch folder:="${folder}" rate:=3.0 loop:=true \
  wait_for_subscribers:=false >"${out}/roslaunch.log" 2>&1 &
launch_pid=$!
trap 'kill ${launch_pid} 2>/dev/null || true; wait ${launch_pid} 2>/dev/null || true' EXIT
status=0
/usr/bin/python3 "${repo}/dasp_ros/scripts/same_results.py" "${folder}" "${out}" 180 || status=$?
exit ${status}
