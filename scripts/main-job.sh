#!/usr/bin/env bash
# Installs the dependencies, builds demlab and runs the main job into runs/.
# usage: scripts/main-job.sh [OUT_DIR]   (default runs/demo; an existing folder is refused)
set -euo pipefail
cd "$(dirname "$0")/.."
bash scripts/install-deps.sh
cmake -S . -B build -G Ninja -DCMAKE_BUILD_TYPE=Release >/dev/null
cmake --build build -j "$(nproc)"
./build/demlab demo --out "${1:-runs/demo}"
