#!/usr/bin/env bash
# Installs every Debian package the workspace needs, from Debian's own archive only.
# Idempotent: when everything is present it returns in about a second without `apt-get update`.
# Waits for the dpkg lock instead of failing; never asks a question.
set -euo pipefail

repo="$(cd "$(dirname "${BASH_SOURCE[0]}")/.." && pwd)"

# What the workspace's code needs comes from its package.xml files: every declared rosdep key, mapped
# to Debian packages by scripts/rosdep_debian.txt (scripts/check_package_deps.py checks that the
# package.xml files are complete). Reading them needs Debian's python3 (pyenv's may come first on PATH).
if [ ! -x /usr/bin/python3 ]; then
  [ "$(id -u)" -eq 0 ] || { echo "install_deps: /usr/bin/python3 missing; run as root" >&2; exit 1; }
  DEBIAN_FRONTEND=noninteractive apt-get -o DPkg::Lock::Timeout=900 update
  DEBIAN_FRONTEND=noninteractive apt-get -o DPkg::Lock::Timeout=900 -y --no-install-recommends \
    install python3-minimal
fi
mapfile -t declared < <(/usr/bin/python3 "${repo}/scripts/check_package_deps.py" --list-debian)
[ ${#declared[@]} -gt 0 ] || { echo "install_deps: no packages read from package.xml" >&2; exit 1; }

# Beyond what any package declares: the tools of the developers' workflow and of `make test`.
packages=(
  "${declared[@]}"
  # build tools (catkin build, compilers, formatting and static analysis)
  build-essential pkg-config git catkin-tools libbenchmark-dev clang-format clang-tidy cppcheck
  # fuzzing (libFuzzer runtime for clang)
  clang libclang-rt-14-dev
  # running launch files and inspecting a running system (roscore, rostopic, rosnode...)
  python3-roslaunch python3-rosnode python3-rosparam python3-rosservice python3-rosmsg
  python3-rostopic python3-rosmaster rosout rosbash topic-tools python3-tf2-msgs
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
