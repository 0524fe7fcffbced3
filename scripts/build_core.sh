#!/usr/bin/env bash
# Builds the ROS-free core (library, gdrhcr_sim, benchmarks, tests) into build/.
set -eo pipefail
top=$(cd "$(dirname "$0")/.." && pwd)
cmake -S "$top" -B "$top/build" -DCMAKE_BUILD_TYPE=Release >/dev/null
cmake --build "$top/build" -j"$(nproc)"
