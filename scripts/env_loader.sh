#!/usr/bin/env bash
# roslaunch env-loader for a remote <machine>: the environment of this workspace, then the command.
# Give roslaunch its absolute path on the remote machine, e.g.
#   roslaunch launch/multi_machine.launch robot_address:=robot robot_env_loader:=/home/robot/ebslam/scripts/env_loader.sh
# ROS_MASTER_URI is passed by roslaunch; ROS_HOSTNAME is the remote machine's own name (set it in
# that machine's environment or with the EBSLAM_ROS_HOSTNAME variable here), never localhost.
repo="$(cd "$(dirname "${BASH_SOURCE[0]}")/.." && pwd)"
ws="${WS_DIR:-${repo}/.ws}"
[ -n "${EBSLAM_ROS_HOSTNAME:-}" ] && export ROS_HOSTNAME="${EBSLAM_ROS_HOSTNAME}"
[ -n "${ROS_HOSTNAME:-}" ] || export ROS_HOSTNAME="$(hostname -f 2>/dev/null || hostname)"
# shellcheck source=ros_env.sh
source "${repo}/scripts/ros_env.sh"
if [ -f "${ws}/install/setup.bash" ] && [ ! -f "${ws}/devel/setup.bash" ]; then
  # shellcheck disable=SC1091
  source "${ws}/install/setup.bash"
else
  # shellcheck disable=SC1091
  source "${ws}/devel/setup.bash"
fi
exec "$@"
