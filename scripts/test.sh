#!/usr/bin/env bash
# Installs the dependencies, builds demlab and its tests, and runs the tests: first the
# Release build (GCC), then the same suite under AddressSanitizer and UndefinedBehaviorSanitizer
# (built with clang, as the fuzz pass is: it compiles the sanitized code in about half GCC's
# time, and the suite's results must not depend on the compiler).
# usage: scripts/test.sh            (what CI runs; the README gives its time on 2 cores)
#        DEMLAB_SANITIZE=0 scripts/test.sh   (skip the sanitizer pass and the fuzz pass)
# Slow validation runs are labelled "slow" and left out: ctest --test-dir build -L slow
set -euo pipefail
cd "$(dirname "$0")/.."
bash scripts/install-deps.sh
jobs="$(nproc)"
cmake -S . -B build -G Ninja -DCMAKE_BUILD_TYPE=Release >/dev/null
cmake --build build -j "$jobs"
ctest --test-dir build --output-on-failure -j "$jobs" -LE slow
if [ "${DEMLAB_SANITIZE:-1}" = "1" ]; then
  echo "== the same suite under AddressSanitizer + UndefinedBehaviorSanitizer"
  cmake -S . -B build-asan -G Ninja -DCMAKE_BUILD_TYPE=Debug -DCMAKE_CXX_COMPILER=clang++ -DDEMLAB_SANITIZE=ON -DCMAKE_CXX_FLAGS=-O1 >/dev/null
  cmake --build build-asan -j "$jobs"
  ASAN_OPTIONS=detect_leaks=1:abort_on_error=1 \
  LSAN_OPTIONS="suppressions=$PWD/tests/lsan.supp" \
  UBSAN_OPTIONS=print_stacktrace=1:halt_on_error=1 \
    ctest --test-dir build-asan --output-on-failure -j "$jobs" -LE slow
  echo "== a short fuzz pass: scenario parsing (10,000 inputs) and random scenarios run (2,000) (libFuzzer)"
  bash scripts/fuzz.sh 10000
fi
