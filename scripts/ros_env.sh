# Sourced by the workspace scripts: an environment in which Debian's ROS 1 works on these machines.
# - pyenv/venv python3 first on PATH breaks catkin and ROS python scripts: drop those entries.
# - roslaunch/rostest need a resolvable own hostname: use localhost.
clean_path=""
IFS=':' read -r -a path_entries <<<"${PATH}"
for entry in "${path_entries[@]}"; do
  case "${entry}" in
    *pyenv* | *virtualenv* | *venv* | *conda* | "") ;;
    *) clean_path="${clean_path:+${clean_path}:}${entry}" ;;
  esac
done
export PATH="${clean_path}"
unset PYTHONPATH VIRTUAL_ENV PYENV_VERSION
export ROS_HOSTNAME="${ROS_HOSTNAME:-localhost}"
export ROS_MASTER_URI="${ROS_MASTER_URI:-http://localhost:11311}"
export ROSCONSOLE_STDOUT_LINE_BUFFERED=1
