#!/usr/bin/env bash
# Installs the dependencies, builds demlab and its tests, and runs the tests.
# usage: scripts/test.sh            (the fast suite: what CI runs)
set -euo pipefail
cd "$(dirname "$0")/.."
bash scripts/install-deps.sh
cmake -S . -B build -G Ninja -DCMAKE_BUILD_TYPE=Release >/dev/null
cmake --build build -j "$(nproc)"
ctest --test-dir build --output-on-failure -j "$(nproc)" -LE slow
