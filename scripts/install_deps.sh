#!/usr/bin/env bash
# Installs every Debian package the workspace needs, from Debian's own archive only.
# Idempotent: when everything is present it returns in about a second without `apt-get update`.
# Waits for the dpkg lock instead of failing; never asks a question.
set -euo pipefail

packages=(
  # build
  build-essential cmake pkg-config git catkin catkin-tools ros-message-generation ros-message-runtime
  libgtest-dev libgmock-dev libbenchmark-dev clang-format clang-tidy cppcheck
  # fuzzing (libFuzzer runtime for clang)
  clang libclang-rt-14-dev
  # ROS client, messages (C++ headers, .msg files, python)
  libroscpp-dev python3-rospy
  libstd-msgs-dev ros-std-msgs python3-std-msgs
  libstd-srvs-dev ros-std-srvs python3-std-srvs
  libgeometry-msgs-dev ros-geometry-msgs python3-geometry-msgs
  libsensor-msgs-dev ros-sensor-msgs python3-sensor-msgs
  libnav-msgs-dev ros-nav-msgs python3-nav-msgs
  libvisualization-msgs-dev ros-visualization-msgs python3-visualization-msgs
  libdiagnostic-msgs-dev ros-diagnostic-msgs python3-diagnostic-msgs
  # tf2
  libtf2-dev libtf2-ros-dev libtf2-geometry-msgs-dev libtf2-eigen-dev python3-tf2-ros python3-tf2-msgs tf2-tools
  # perception
  libcv-bridge-dev libimage-transport-dev libpcl-conversions-dev libpcl-ros-dev
  libcamera-info-manager-dev libcamera-calibration-parsers-dev libdiagnostic-updater-dev
  # tools
  python3-roslaunch python3-rostest librostest-dev python3-rosunit librosbag-dev librosbag-storage-dev
  python3-rosbag python3-rostopic python3-rosnode python3-rosparam python3-rosservice python3-rosmsg
  python3-rosmaster rosout rosbash topic-tools python3-message-filters
  libdynamic-reconfigure-config-init-mutex-dev python3-dynamic-reconfigure
  libnodeletlib-dev libnodelet-dev libnodeletlib-tools libclass-loader-dev
  rviz
  # libraries
  libeigen3-dev libopencv-dev libopencv-contrib-dev libpcl-dev libopenni2-dev libusb-1.0-0-dev
  libspectra-dev libceres-dev libtbb-dev libcli11-dev nlohmann-json3-dev libserialport-dev
  python3-matplotlib python3-numpy
  # headless viewing and hostname resolution
  xvfb xauth libgl1-mesa-dri imagemagick hostname
)

# roslaunch/rostest need localhost to resolve (ROS_HOSTNAME=localhost is set by scripts/ros_env.sh).
if ! getent hosts localhost >/dev/null 2>&1; then
  if [ -w /etc/hosts ]; then
    echo "127.0.0.1 localhost" >>/etc/hosts
    echo "install_deps: added localhost to /etc/hosts"
  else
    echo "install_deps: warning: 'localhost' does not resolve; roslaunch will fail" >&2
  fi
fi

missing=()
for p in "${packages[@]}"; do
  if ! dpkg-query -W -f='${Status}' "$p" 2>/dev/null | grep -q "install ok installed"; then
    missing+=("$p")
  fi
done

if [ ${#missing[@]} -eq 0 ]; then
  echo "install_deps: all ${#packages[@]} packages present"
  exit 0
fi

echo "install_deps: installing ${#missing[@]} missing packages: ${missing[*]}"
if [ "$(id -u)" -ne 0 ]; then
  echo "install_deps: must run as root (or install the packages above by hand)" >&2
  exit 1
fi
export DEBIAN_FRONTEND=noninteractive
apt_opts=(-o DPkg::Lock::Timeout=900 -o Acquire::Retries=3 -y --no-install-recommends)
apt-get "${apt_opts[@]:0:4}" update
apt-get "${apt_opts[@]}" install "${missing[@]}"
echo "install_deps: done"
