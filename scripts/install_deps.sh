#!/usr/bin/env bash
# Installs what gd_rhcr needs from Debian 12's archive (run as root; no-op when all present).
# Core: compiler, CMake, GoogleTest, oneTBB, nlohmann-json. ROS 1 from Debian (see
# ../shared/ROS_ON_DEBIAN.md): catkin, roscpp, messages, actionlib, tf2, rostest, roslaunch.
# Tools: matplotlib for plots; Dask distributed, the sweep backend of tools/gdrhcr_sweep.py;
# clang and its libFuzzer runtime for scripts/fuzz.sh. Extra packages listed in
# scripts/ros_deps.txt are added too.
set -eo pipefail
here=$(cd "$(dirname "$0")" && pwd)
pkgs=(
  build-essential cmake libgtest-dev googletest libgmock-dev libtbb-dev nlohmann-json3-dev
  libyaml-cpp-dev python3-matplotlib python3-numpy python3-yaml python3-distributed python3-dask
  clang libclang-rt-14-dev
  catkin ros-message-generation ros-message-runtime libroscpp-dev python3-rospy
  ros-std-msgs libstd-msgs-dev python3-std-msgs
  ros-geometry-msgs libgeometry-msgs-dev python3-geometry-msgs
  ros-nav-msgs libnav-msgs-dev python3-nav-msgs
  ros-visualization-msgs libvisualization-msgs-dev python3-visualization-msgs
  ros-actionlib-msgs libactionlib-msgs-dev python3-actionlib-msgs
  ros-diagnostic-msgs libdiagnostic-msgs-dev python3-diagnostic-msgs
  libactionlib-dev python3-actionlib
  libtf2-dev libtf2-ros-dev libtf2-geometry-msgs-dev python3-tf2-ros ros-tf2-msgs libtf2-msgs-dev
  librostest-dev python3-rostest python3-roslaunch python3-rosmaster rosout rosbash
  python3-rostopic python3-rosbag python3-rosnode python3-rosservice python3-rosparam python3-rosmsg
)
if [ -f "$here/ros_deps.txt" ]; then
  while read -r p; do
    p=${p%%#*}
    for w in $p; do pkgs+=("$w"); done
  done <"$here/ros_deps.txt"
fi
missing=()
for p in "${pkgs[@]}"; do
  dpkg-query -W -f='${Status}' "$p" 2>/dev/null | grep -q "install ok installed" || missing+=("$p")
done
if [ ${#missing[@]} -eq 0 ]; then
  echo "install_deps: all ${#pkgs[@]} packages present"
  exit 0
fi
echo "install_deps: installing ${#missing[@]} packages: ${missing[*]}"
sudo_cmd=()
[ "$(id -u)" -ne 0 ] && sudo_cmd=(sudo)
"${sudo_cmd[@]}" apt-get update -qq
DEBIAN_FRONTEND=noninteractive "${sudo_cmd[@]}" apt-get install -y -qq "${missing[@]}" >/dev/null
echo "install_deps: done"
