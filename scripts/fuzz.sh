#!/usr/bin/env bash
# Fuzzes scenario parsing and validation with libFuzzer (clang) under ASan and UBSan,
# seeded with scenarios/*.toml.   usage: scripts/fuzz.sh [RUNS]   (default 10000 inputs)
# Findings (crashing inputs) are written to build-fuzz/ as crash-*; the run fails on one.
set -euo pipefail
cd "$(dirname "$0")/.."
runs="${1:-10000}"
cmake -S . -B build-fuzz -G Ninja -DCMAKE_BUILD_TYPE=Debug -DCMAKE_CXX_COMPILER=clang++ -DCMAKE_CXX_FLAGS=-O1 \
  -DDEMLAB_FUZZ=ON -DDEMLAB_SANITIZE=ON -DDEMLAB_TESTS=OFF >/dev/null
cmake --build build-fuzz --target fuzz_scenario -j "$(nproc)"
corpus=build-fuzz/corpus
mkdir -p "$corpus"
cp scenarios/*.toml "$corpus/"
cd build-fuzz
UBSAN_OPTIONS=halt_on_error=1:print_stacktrace=1 ./fuzz_scenario -runs="$runs" -max_total_time=600 \
  -timeout=10 -rss_limit_mb=2048 -print_final_stats=1 corpus 2>&1 | tail -25
