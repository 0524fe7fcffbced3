#!/usr/bin/env bash
# Builds (scripts/ros_build.sh) and runs every ROS test: gtest units, rostest integration tests
# (planner + fleet_sim + task generator, headless) and roslaunch file checks. Exits non-zero on a
# failed build, a failed test, or when no test ran at all (catkin_make run_tests exits 0 on
# failures: ROS_ON_DEBIAN.md pitfall 3, so catkin_test_results decides).
#   bash scripts/ros_test.sh
set -o pipefail
top=$(cd "$(dirname "$0")/.." && pwd)
ws="${GDRHCR_WS:-$top/.ws}"  # GDRHCR_WS: another workspace (parallel work in one checkout)
export PATH=/usr/bin:$PATH
export ROS_HOME="$ws/.ros_home" ROS_IP=127.0.0.1
bash "$top/scripts/ros_build.sh" || { echo "ros_test: build failed"; exit 1; }
cd "$ws" || exit 1
# shellcheck disable=SC1091
source devel/setup.bash  # not under set -u (pitfall 5)
rm -rf build/test_results
catkin_make run_tests -j"${ROS_BUILD_JOBS:-2}" -DPYTHON_EXECUTABLE=/usr/bin/python3 2>&1 | tee "$ws/run_tests.log" | \
  grep -E "^\[ *(OK|FAILED|RUN|PASSED)|SUMMARY|\* RESULT|\* TESTS|\* ERRORS|\* FAILURES|Error|FAILURE" || true
echo
summary=$(catkin_test_results build/test_results 2>&1)
rc=$?
catkin_test_results --verbose build/test_results 2>&1 | grep -vE "^Skipping" | tail -40
echo "$summary" | tail -1
total=$(echo "$summary" | grep -oE '^Summary: [0-9]+ tests' | grep -oE '[0-9]+')
if [ "$rc" -ne 0 ]; then echo "ros_test: FAILED"; exit 1; fi
if [ -z "$total" ] || [ "$total" -eq 0 ]; then echo "ros_test: no tests ran"; exit 1; fi
echo "ros_test: all $total tests passed"
