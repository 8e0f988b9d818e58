# Sourced by the measurement scripts of this folder (not run on its own): the built workspace's
# environment (.ws, or WS_DIR) and a ROS master of their own on a free local port, waited for
# until it answers. Sets ROS_MASTER_URI and ros_master_pid (the caller's EXIT trap kills it).
repo="$(cd "$(dirname "${BASH_SOURCE[0]}")/../.." && pwd)"
source "${repo}/scripts/ros_env.sh"
set +u
source "${WS_DIR:-${repo}/.ws}/devel/setup.bash"
export ROS_HOSTNAME=localhost
ros_master_port=$(/usr/bin/python3 -c 'import socket; s=socket.socket(); s.bind(("",0)); print(s.getsockname()[1])')
export ROS_MASTER_URI=http://localhost:${ros_master_port}
roscore -p "${ros_master_port}" >/dev/null 2>&1 &
ros_master_pid=$!
for _ in $(seq 50); do rostopic list >/dev/null 2>&1 && break; sleep 0.2; done
