#!/usr/bin/env bash
# The core's tests under AddressSanitizer + UndefinedBehaviorSanitizer, and the parallel
# planner's tests under ThreadSanitizer. Any report fails the run.
set -eo pipefail
top=$(cd "$(dirname "$0")/.." && pwd)
jobs=$(nproc)
export ASAN_OPTIONS=detect_leaks=1:abort_on_error=1
export UBSAN_OPTIONS=halt_on_error=1:print_stacktrace=1
# report_atomic_races=0: oneTBB's inline header code decrements its wait contexts (on the
# waiting thread's stack) atomically, and the matching acquire happens inside libtbb, which TSan
# does not see; the stack memory reused after the join was reported as a race with that atomic
# write (CI, session 4: "Previous atomic write ... by thread T1 [failed to restore the stack]").
# Our own code never mixes atomic and plain accesses to one location. history_size=7 keeps the
# earlier access's stack restorable, so test/tsan.supp can match TBB frames in it.
export TSAN_OPTIONS="halt_on_error=1:second_deadlock_stack=1:report_atomic_races=0:history_size=7:suppressions=$top/test/tsan.supp"

echo "--- ASan + UBSan build"
cmake -S "$top" -B "$top/build-asan" -DCMAKE_BUILD_TYPE=RelWithDebInfo -DGDRHCR_SANITIZE=address,undefined \
  -DCMAKE_CXX_FLAGS=-fno-sanitize-recover=undefined >/dev/null
cmake --build "$top/build-asan" -j"$jobs" --target gdrhcr_core_tests gdrhcr_sim deadline_planner_tests
"$top/build-asan/test/gdrhcr_core_tests" --gtest_brief=1
"$top/build-asan/test/deadline_planner_tests" --gtest_brief=1

echo "--- TSan build (parallel GD-RHCR, the windowed LNS's zones, the search over operations' halves, the shared distance table, the node's DeadlinePlanner)"
cmake -S "$top" -B "$top/build-tsan" -DCMAKE_BUILD_TYPE=RelWithDebInfo -DGDRHCR_SANITIZE=thread >/dev/null
cmake --build "$top/build-tsan" -j"$jobs" --target gdrhcr_core_tests deadline_planner_tests
"$top/build-tsan/test/gdrhcr_core_tests" --gtest_brief=1 --gtest_filter='GdRhcr*:DistTable*:ImmovableAgents*:WindowLns.Zones*:RotationPlanners.OperationsSearch*'
"$top/build-tsan/test/deadline_planner_tests" --gtest_brief=1
echo "sanitizer tests: clean"
