#!/usr/bin/env bash
# Fuzzes the map parsers with libFuzzer (ASan + UBSan): builds test/fuzz in build-fuzz with clang
# and runs each target for FUZZ_SECONDS (default 60) seconds, seeded from maps/ and test/data/.
# The growing corpus is kept in build-fuzz/corpus/<target>; a crash, hang or sanitizer report
# leaves its input in build-fuzz/artifacts/ and fails the script. Turn such an input into a
# regression file: copy it to test/data/fuzz_regressions/ (fuzz_regressions_test replays them).
#   bash scripts/fuzz.sh                      # every target, 60 s each
#   FUZZ_SECONDS=20 bash scripts/fuzz.sh fuzz_map
set -eo pipefail
top=$(cd "$(dirname "$0")/.." && pwd)
build="$top/build-fuzz"
secs=${FUZZ_SECONDS:-60}
targets=("$@")
[ ${#targets[@]} -eq 0 ] && targets=(fuzz_movingai fuzz_kiva fuzz_map fuzz_cell_list)
command -v clang++ >/dev/null || { echo "fuzz: clang++ not found (scripts/install_deps.sh installs clang)"; exit 1; }

echo "--- building fuzz targets in $build"
CC=clang CXX=clang++ cmake -S "$top" -B "$build" -DCMAKE_BUILD_TYPE=RelWithDebInfo -DGDRHCR_FUZZ=ON \
  -DBUILD_TESTING=OFF >/dev/null
cmake --build "$build" -j"$(nproc)" --target "${targets[@]}" >/dev/null

# Seeds: every map, MAPD side file and test data file (a read-only corpus directory).
seeds="$build/seeds"
rm -rf "$seeds"
mkdir -p "$seeds" "$build/artifacts"
n=0
while IFS= read -r -d '' f; do
  cp "$f" "$seeds/seed-$n"
  n=$((n + 1))
done < <(find "$top/maps" "$top/test/data" -type f \( -name '*.map' -o -name '*.pickups' \
           -o -name '*.deliveries' -o -path '*/test/data/*' \) -size -64k -print0 | sort -z)
echo "--- $n seed files; $secs s per target"

export ASAN_OPTIONS=abort_on_error=1:detect_leaks=1
export UBSAN_OPTIONS=halt_on_error=1:print_stacktrace=1
failed=()
for t in "${targets[@]}"; do
  corpus="$build/corpus/$t"
  mkdir -p "$corpus"
  log="$build/$t.log"
  if "$build/test/fuzz/$t" "$corpus" "$seeds" -dict="$top/test/fuzz/maps.dict" \
       -max_total_time="$secs" -timeout=10 -rss_limit_mb=2048 -max_len=8192 \
       -artifact_prefix="$build/artifacts/$t-" -print_final_stats=1 >"$log" 2>&1; then
    runs=$(grep -oE 'stat::number_of_executed_units: *[0-9]+' "$log" | grep -oE '[0-9]+$' || echo '?')
    cov=$(grep -oE 'cov: [0-9]+ ft: [0-9]+' "$log" | tail -1)
    echo "$t: clean, $runs runs, $cov, corpus $(ls "$corpus" | wc -l) inputs"
  else
    failed+=("$t")
    echo "$t: FAILED (log $log)"
    grep -E 'ERROR|SUMMARY|Test unit written|==[0-9]+==' "$log" | head -20 || true
    tail -n 30 "$log"
  fi
done
if [ ${#failed[@]} -gt 0 ]; then
  echo "fuzz: FAILED: ${failed[*]}; inputs in $build/artifacts/"
  exit 1
fi
echo "fuzz: clean"
