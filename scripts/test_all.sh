#!/usr/bin/env bash
# The README's test command: installs what is missing, builds everything, runs every test and
# exits non-zero on any failure (or when a suite ran no test at all).
#   bash scripts/test_all.sh
set -o pipefail
top=$(cd "$(dirname "$0")/.." && pwd)
cd "$top"
export PATH=/usr/bin:$PATH  # Debian's python3 first (ROS_ON_DEBIAN.md pitfall 1)
failed=()
total_pass=0
total_fail=0

section() { printf '\n=== %s ===\n' "$*"; }

section "dependencies"
bash scripts/install_deps.sh || { echo "dependency install failed"; exit 1; }

section "core: build"
if ! bash scripts/build_core.sh; then
  echo "core build failed"
  exit 1
fi

section "core: tests (ctest)"
ctest --test-dir build --output-on-failure -j2 2>&1 | tee build/ctest.log
ctest_rc=${PIPESTATUS[0]}
core_total=$(grep -oE 'out of [0-9]+' build/ctest.log | tail -1 | grep -oE '[0-9]+')
core_failed=$(grep -oE '[0-9]+ tests failed' build/ctest.log | tail -1 | grep -oE '^[0-9]+')
core_total=${core_total:-0}
core_failed=${core_failed:-0}
if [ "$ctest_rc" -ne 0 ] || [ "$core_total" -eq 0 ]; then failed+=("core tests"); fi
total_pass=$((total_pass + core_total - core_failed))
total_fail=$((total_fail + core_failed))

export FUZZ_SECONDS=${FUZZ_SECONDS:-15}  # scripts/fuzz.sh: a short run per target here
for extra in scripts/sanitizer_tests.sh scripts/fuzz.sh scripts/lorr_test.sh scripts/ros_build.sh scripts/ros_test.sh; do
  [ -x "$extra" ] || continue
  section "$extra"
  if bash "$extra"; then total_pass=$((total_pass + 1)); else failed+=("$extra"); total_fail=$((total_fail + 1)); fi
done

section "summary"
if [ ${#failed[@]} -gt 0 ]; then
  echo "FAILED: ${failed[*]}"
fi
echo "$total_pass passed, $total_fail failed"
[ ${#failed[@]} -eq 0 ]
