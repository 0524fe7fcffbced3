#!/usr/bin/env bash
# The README's main command: installs what is missing, builds the core and the catkin packages,
# and runs the simulated warehouse (planner node + simulated fleet + MAPD task generator) with
# GD-RHCR. With a display it opens rviz and runs until Ctrl-C; headless it runs DURATION
# seconds (default 120) and prints a summary.
#   bash scripts/run_warehouse.sh
#   PLANNER=rhcr ROBOTS=200 DURATION=300 bash scripts/run_warehouse.sh [extra roslaunch args]
# Extra arguments go to `roslaunch gd_rhcr_planner warehouse_sim.launch`, e.g. map:=/abs/x.map
set -eo pipefail
top=$(cd "$(dirname "$0")/.." && pwd)
cd "$top"
PLANNER=${PLANNER:-gd-rhcr}
ROBOTS=${ROBOTS:-100}
if [ -n "${DISPLAY:-}" ]; then
  rviz=true
  DURATION=${DURATION:-0}
else
  rviz=false
  DURATION=${DURATION:-120}
fi

bash scripts/install_deps.sh
if [ "$rviz" = true ] && ! command -v rviz >/dev/null; then
  echo "run_warehouse: installing rviz for the display"
  DEBIAN_FRONTEND=noninteractive apt-get install -y -qq rviz >/dev/null || rviz=false
fi
bash scripts/ros_build.sh >/tmp/gdrhcr_ros_build.log 2>&1 || { tail -30 /tmp/gdrhcr_ros_build.log; echo "run_warehouse: build failed"; exit 1; }

export PATH=/usr/bin:$PATH
export ROS_HOME="$top/.ws/.ros_home" ROS_IP=127.0.0.1
export ROS_MASTER_URI=${ROS_MASTER_URI:-http://127.0.0.1:11311}
# shellcheck disable=SC1091
source "$top/.ws/devel/setup.bash"

echo "run_warehouse: planner=$PLANNER robots=$ROBOTS rviz=$rviz duration=${DURATION}s (0 = until Ctrl-C)"
roslaunch gd_rhcr_planner warehouse_sim.launch planner:="$PLANNER" num_robots:="$ROBOTS" rviz:="$rviz" \
  output:=log "$@" &
launch_pid=$!
stop() { kill -INT "$launch_pid" 2>/dev/null || true; wait "$launch_pid" 2>/dev/null || true; }
trap 'stop; exit 130' INT TERM

field() { timeout 5 rostopic echo -n 1 "/planner_stats/$1" 2>/dev/null | head -1; }
start=$(date +%s)
last=""
while kill -0 "$launch_pid" 2>/dev/null; do
  sleep 10
  now=$(( $(date +%s) - start ))
  tick=$(field tick); delivered=$(field tasks_delivered); queued=$(field tasks_queued)
  plan=$(field plan_time); overruns=$(field overruns); groups=$(field num_groups)
  if [ -n "$tick" ]; then
    last="tick $tick, delivered $delivered, queued $queued, groups $groups, plan time ${plan}s, overruns $overruns"
    echo "[$now s] $last"
  else
    echo "[$now s] waiting for the planner..."
  fi
  if [ "$DURATION" -gt 0 ] && [ "$now" -ge "$DURATION" ]; then break; fi
done
if ! kill -0 "$launch_pid" 2>/dev/null; then
  wait "$launch_pid"; rc=$?
  echo "run_warehouse: roslaunch exited with $rc (logs in $ROS_HOME/log)"
  exit 1
fi
stop
echo "run_warehouse: done after ${DURATION}s: $last"
