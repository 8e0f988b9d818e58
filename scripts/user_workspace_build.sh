#!/usr/bin/env bash
# Builds this repository as a ROS user would: copied into the src/ of a fresh workspace of their own,
# once with `catkin build` and once with `catkin_make_isolated --install`, then checks that the
# packages are found and a launch file resolves from the result. A documented run, not part of
# `make test` (each build takes the whole workspace: tens of minutes on 2 shared cores).
#   scripts/user_workspace_build.sh [WORK_DIR]     (default: a new folder under /tmp)
# Environment: JOBS (default: number of cores), TOOLS (default "catkin_build catkin_make_isolated"),
# REF (default HEAD, the committed tree; `git write-tree` gives the staged one).
# Prints one line per tool, "user_workspace: <tool> ok|FAILED (<seconds> s)"; exit 1 if any failed.
set -eo pipefail

repo="$(cd "$(dirname "${BASH_SOURCE[0]}")/.." && pwd)"
work="${1:-$(mktemp -d /tmp/user_ws.XXXXXX)}"
jobs="${JOBS:-$(nproc)}"
tools="${TOOLS:-catkin_build catkin_make_isolated}"
ref="${REF:-HEAD}"  # the commit or tree copied into the workspace
# shellcheck source=ros_env.sh
source "${repo}/scripts/ros_env.sh"
# Debian's pluginlib uses FindPython3: both variables point at Debian's interpreter (a pyenv one
# would be found otherwise; see docs/building.md).
python_args=(-DPYTHON_EXECUTABLE=/usr/bin/python3 -DPython3_EXECUTABLE=/usr/bin/python3)

# A user's workspace: their own package beside a clone of this repository.
make_workspace() {
  local ws="$1"
  rm -rf "${ws}"
  mkdir -p "${ws}/src/ebslam_repo"
  # The committed tree, as a clone would have it (no build folders, no local files).
  git -C "${repo}" archive "${ref}" | tar -x -C "${ws}/src/ebslam_repo"
  # The user's own package, depending on ours through find_package(catkin COMPONENTS ...).
  mkdir -p "${ws}/src/my_robot/src"
  cat >"${ws}/src/my_robot/package.xml" <<'EOF'
<?xml version="1.0"?>
<package format="3">
  <name>my_robot</name>
  <version>0.0.1</version>
  <description>A user's package that uses the event-based SLAM messages.</description>
  <maintainer email="user@example.com">user</maintainer>
  <license>MIT</license>
  <buildtool_depend>catkin</buildtool_depend>
  <depend>roscpp</depend>
  <depend>ebslam_msgs</depend>
</package>
EOF
  cat >"${ws}/src/my_robot/CMakeLists.txt" <<'EOF'
cmake_minimum_required(VERSION 3.16)
project(my_robot)
find_package(catkin REQUIRED COMPONENTS roscpp ebslam_msgs)
catkin_package()
add_executable(count_events src/count_events.cpp)
target_include_directories(count_events PRIVATE ${catkin_INCLUDE_DIRS})
target_link_libraries(count_events ${catkin_LIBRARIES})
add_dependencies(count_events ${catkin_EXPORTED_TARGETS})
EOF
  cat >"${ws}/src/my_robot/src/count_events.cpp" <<'EOF'
#include <ebslam_msgs/EventArray.h>
#include <ros/ros.h>

void onEvents(const ebslam_msgs::EventArray::ConstPtr& msg) {
  ROS_INFO_THROTTLE(1.0, "%zu events", msg->events.size());
}

int main(int argc, char** argv) {
  ros::init(argc, argv, "count_events");
  ros::NodeHandle nh;
  ros::Subscriber sub = nh.subscribe("events", 10, onEvents);
  ros::spin();
  return 0;
}
EOF
}

# After a build: the setup file finds our packages, the user's node and a launch file's includes.
smoke() {
  local setup="$1"
  (
    cd /tmp
    set +u
    # shellcheck disable=SC1090
    source "${setup}"
    set -e
    for pkg in ebslam_msgs ebslam_ros dasp_ros edvs_driver my_robot; do
      echo "  rospack find ${pkg}: $(rospack find "${pkg}")"
    done
    local launch
    for launch in "ebslam_ros simulation.launch" "ebslam_ros simulated_localisation.launch" \
                  "edvs_driver edvs.launch"; do
      # shellcheck disable=SC2086
      echo "  roslaunch --files ${launch}: $(roslaunch --files ${launch} | wc -l) files"
    done
    test -n "$(rospack plugins --attrib=plugin nodelet | grep ebslam_ros)"
  )
}

status=0
summary=()
for tool in ${tools}; do
  ws="${work}/${tool}"
  make_workspace "${ws}"
  start=$(date +%s)
  result=ok
  echo "=== ${tool} in ${ws}"
  case "${tool}" in
    catkin_build)
      (cd "${ws}" && catkin init >/dev/null && catkin config --cmake-args "${python_args[@]}" >/dev/null \
        && catkin build -j "${jobs}" --no-status --no-notify --summarize) >"${ws}/build.log" 2>&1 \
        || result=FAILED
      setup="${ws}/devel/setup.bash"
      ;;
    catkin_make_isolated)
      (cd "${ws}" && catkin_make_isolated --install -j"${jobs}" --cmake-args "${python_args[@]}") \
        >"${ws}/build.log" 2>&1 || result=FAILED
      setup="${ws}/install_isolated/setup.bash"
      ;;
    *) echo "unknown tool ${tool}" >&2; exit 2 ;;
  esac
  tail -n 15 "${ws}/build.log"
  if [ "${result}" = ok ]; then
    smoke "${setup}" || result=FAILED
  fi
  [ "${result}" = ok ] || status=1
  summary+=("user_workspace: ${tool} ${result} ($(($(date +%s) - start)) s)")
done
printf '%s\n' "${summary[@]}"
exit "${status}"
