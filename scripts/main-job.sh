#!/usr/bin/env bash
# Installs the dependencies, builds demlab and runs the main job: flume geometry A of the
# thesis (scale 4, 9,101 discs, Model 3, Variant II) from the release to rest, with a PNG
# frame at every snapshot (frames/) and the force, front and energy plots (plots/).
# usage: scripts/main-job.sh [OUT_DIR] [extra demlab run options]
#   default OUT_DIR runs/geometry-A; an existing folder is refused (give another, or --force)
#   a quick look: scripts/main-job.sh runs/geometry-A-20 --scale 20   (364 discs, seconds)
# Runs on 2 threads when the machine has 2 cores or more (same bits as 1 thread, 1.7x faster
# on this run: docs/performance.md); give --threads to choose.
# A checkpoint is written every 5 minutes and on Ctrl-C: `./build/demlab resume OUT_DIR`
# continues an interrupted run to the same results.
set -euo pipefail
cd "$(dirname "$0")/.."
bash scripts/install-deps.sh
cmake -S . -B build -G Ninja -DCMAKE_BUILD_TYPE=Release >/dev/null
cmake --build build -j "$(nproc)"
out="${1:-runs/geometry-A}"
shift || true
threads=()
if [[ " $* " != *" --threads"* ]]; then
    cores="$(nproc)"
    threads=(--threads "$(( cores < 2 ? cores : 2 ))")
fi
./build/demlab run scenarios/geometry-A.toml --out "$out" --frames --checkpoint-every 300 "${threads[@]}" "$@"
