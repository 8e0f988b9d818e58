#!/usr/bin/env bash
# Runs launch/demo.launch headless on the sample session, records its outputs into demo_output/
# and prints a summary (also written to demo_output/summary.txt). Assumes `scripts/ws.sh build`.
set -eo pipefail
repo="$(cd "$(dirname "${BASH_SOURCE[0]}")/.." && pwd)"
ws="${WS_DIR:-${repo}/.ws}"
out="${repo}/demo_output"
source "${repo}/scripts/ros_env.sh"
set +u
# shellcheck disable=SC1091
source "${ws}/devel/setup.bash"
rm -rf "${out}"
mkdir -p "${out}"
# A master of our own on a free port, so the demo never talks to another running ROS system.
port=$(/usr/bin/python3 -c 'import socket; s=socket.socket(); s.bind(("localhost", 0)); print(s.getsockname()[1])')
export ROS_MASTER_URI="http://localhost:${port}"
export ROS_LOG_DIR="${out}/logs"
echo "demo: running launch/demo.launch (master on port ${port}); outputs in ${out}"
roslaunch -p "${port}" "${repo}/launch/demo.launch" output_dir:="${out}" >"${out}/roslaunch.log" 2>&1 || {
  echo "demo: roslaunch failed, see ${out}/roslaunch.log" >&2
  tail -n 30 "${out}/roslaunch.log" >&2
  exit 1
}
/usr/bin/python3 "${repo}/scripts/demo_summary.py" "${out}" | tee "${out}/summary.txt"
