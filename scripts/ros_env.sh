#!/usr/bin/env bash
# Sourced by the ROS benchmark and soak scripts, so each works in a fresh clone: installs what is
# missing (scripts/install_deps.sh, a no-op when everything is there), builds the catkin workspace
# incrementally (scripts/ros_build.sh; its log in $ws/ros_build.log) and sources it.
#   source "$top/scripts/ros_env.sh"     # with $top the repository; sets $ws
# GDRHCR_WS: another workspace; GDRHCR_SKIP_BUILD=1: use the workspace as it is.
ws="${GDRHCR_WS:-$top/.ws}"
export PATH=/usr/bin:$PATH ROS_HOME="$ws/.ros_home" ROS_IP=127.0.0.1
if [ "${GDRHCR_SKIP_BUILD:-0}" != 1 ]; then
  bash "$top/scripts/install_deps.sh" >/dev/null || { echo "$(basename "$0"): installing dependencies failed (bash scripts/install_deps.sh)" >&2; exit 1; }
  mkdir -p "$ws"
  if ! bash "$top/scripts/ros_build.sh" >"$ws/ros_build.log" 2>&1; then
    tail -20 "$ws/ros_build.log" >&2
    echo "$(basename "$0"): building the workspace failed (bash scripts/ros_build.sh; log $ws/ros_build.log)" >&2
    exit 1
  fi
fi
if [ ! -f "$ws/devel/setup.bash" ]; then
  echo "$(basename "$0"): no workspace at $ws: run bash scripts/ros_build.sh first" >&2
  exit 1
fi
mkdir -p "$ROS_HOME"
# shellcheck disable=SC1091
source "$ws/devel/setup.bash"
