#!/usr/bin/env bash
# Builds the catkin packages (gd_rhcr_msgs, gd_rhcr_planner, fleet_sim) in the workspace .ws/
# at the repository top (gitignored): .ws/src holds symlinks to the packages, so edits in the
# repository are picked up directly. Follows shared ROS_ON_DEBIAN.md (Debian 12 ROS 1 packages).
#   bash scripts/ros_build.sh            # incremental
#   bash scripts/ros_build.sh --clean    # wipe .ws/build and .ws/devel first
# Afterwards: source .ws/devel/setup.bash (not under `set -u`).
set -eo pipefail
top=$(cd "$(dirname "$0")/.." && pwd)
ws="${GDRHCR_WS:-$top/.ws}"  # GDRHCR_WS: another workspace (parallel work in one checkout)
export PATH=/usr/bin:$PATH                     # pitfall 1: Debian's python3 first
export ROS_HOME="$ws/.ros_home" ROS_IP=127.0.0.1 ROS_MASTER_URI=${ROS_MASTER_URI:-http://127.0.0.1:11311}
jobs=${ROS_BUILD_JOBS:-2}

if [ "${1:-}" = "--clean" ]; then rm -rf "$ws/build" "$ws/devel"; shift; fi
mkdir -p "$ws/src" "$ROS_HOME"
for pkg in gd_rhcr_msgs gd_rhcr_planner fleet_sim; do
  ln -sfn "$top/$pkg" "$ws/src/$pkg"
done
[ -e "$ws/src/CMakeLists.txt" ] || ln -s /usr/share/catkin/cmake/toplevel.cmake "$ws/src/CMakeLists.txt"
mkdir -p "$ws/devel/lib/python3/dist-packages"  # pitfall 2: before the first configure

cd "$ws"
catkin_make -j"$jobs" -DPYTHON_EXECUTABLE=/usr/bin/python3 -DCMAKE_BUILD_TYPE=Release "$@"
