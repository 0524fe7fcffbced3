#!/usr/bin/env bash
# The README screenshot: warehouse_sim.launch with rviz under Xvfb (no display needed), captured
# after WAIT seconds of the busy default load.
#   bash scripts/rviz_screenshot.sh [out.png]      # ROBOTS=300 WAIT=60 PLANNER=gd-rhcr
# Runs a ROS master on a fixed port: take the team's lock (flock /tmp/gdrhcr_ros.lock ...).
set -eo pipefail
top=$(cd "$(dirname "$0")/.." && pwd)
ws="${GDRHCR_WS:-$top/.ws}"
out=$(realpath -m "${1:-$top/docs/rviz_warehouse.png}")
export PATH=/usr/bin:$PATH ROS_HOME="$ws/.ros_home" ROS_IP=127.0.0.1 ROS_MASTER_URI=http://127.0.0.1:11399
# shellcheck disable=SC1091
source "$ws/devel/setup.bash"
disp=:${XVFB_DISPLAY:-97}
Xvfb "$disp" -screen 0 1280x800x24 >/dev/null 2>&1 &
xvfb=$!
sleep 2
DISPLAY=$disp roslaunch -p 11399 gd_rhcr_planner warehouse_sim.launch num_robots:="${ROBOTS:-300}" \
  planner:="${PLANNER:-gd-rhcr}" task_store:=none output:=log >/tmp/rviz_screenshot.log 2>&1 &
launch=$!
sleep "${WAIT:-60}"
DISPLAY=$disp import -window root "$out"
kill -INT "$launch" 2>/dev/null || true
wait "$launch" 2>/dev/null || true
kill "$xvfb" 2>/dev/null || true
echo "rviz_screenshot: $out"
