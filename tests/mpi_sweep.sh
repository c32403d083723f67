#!/usr/bin/env bash
# Sweeps under MPI (CTest: calibration.mpi): `mpirun -n 2` gives the same calibration
# table.csv and table.md bytes as `--jobs 1`, a calibration resumed with another number of
# ranks computes nothing already finished, and `demlab sweep` gives the same sweep.csv.
# usage: tests/mpi_sweep.sh DEMLAB_EXE WORK_DIR
set -euo pipefail
exe="$1"
work="$2"
cd "$(dirname "$0")/.."
rm -rf "$work"
mkdir -p "$work"
mpi=(mpirun --oversubscribe -n 2)
if [ "$(id -u)" -eq 0 ]; then mpi+=(--allow-run-as-root); fi
sweep=(calibrate calibration/dam-break.toml --scale 20 --no-refine)
"$exe" "${sweep[@]}" --angles 15,17 --jobs 1 --out "$work/one" > "$work/one.log"
"${mpi[@]}" "$exe" "${sweep[@]}" --angles 15,17 --jobs 1 --out "$work/two" > "$work/two.log"
cmp "$work/one/table.csv" "$work/two/table.csv"
cmp "$work/one/table.md" "$work/two/table.md"
# each rank ran one of the two runs
test "$(grep -c '^rank [01] of 2' "$work/two.log")" -eq 2
# resumed on one rank with a third angle: only that one is new
"$exe" "${sweep[@]}" --angles 15,16,17 --jobs 1 --out "$work/two" > "$work/resume.log"
grep -q '1 new run(s), 2 reused' "$work/resume.log"
# and back on two ranks: nothing new at all (rank 0 reports its share: all reused)
"${mpi[@]}" "$exe" "${sweep[@]}" --angles 15,16,17 --jobs 1 --out "$work/two" > "$work/again.log"
grep -q ' 0 new run(s)' "$work/again.log"
"$exe" "${sweep[@]}" --angles 15,16,17 --jobs 1 --out "$work/three" > "$work/three.log"
cmp "$work/three/table.csv" "$work/two/table.csv"
cmp "$work/three/table.md" "$work/two/table.md"
# demlab sweep: the same sweep.csv on 1 and 2 ranks
cat > "$work/s.toml" <<TOML
[sweep]
scenario = "$PWD/scenarios/geometry-A.toml"
set = ["release.scale=20", "stop.t_max=0.4", "output.snapshot_interval=0"]
[grid]
"material.friction_disc_deg" = [14, 17]
"rotation.model" = [1, 3]
TOML
"$exe" sweep "$work/s.toml" --jobs 1 --out "$work/sweep-one" > "$work/sweep-one.log"
"${mpi[@]}" "$exe" sweep "$work/s.toml" --jobs 1 --out "$work/sweep-two" > "$work/sweep-two.log"
cmp "$work/sweep-one/sweep.csv" "$work/sweep-two/sweep.csv"
test "$(wc -l < "$work/sweep-two/sweep.csv")" -eq 5
echo "mpi: the same calibration tables and sweep.csv on 1 and 2 ranks, resumed across rank counts without recomputing"
