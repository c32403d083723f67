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
# bad input found by rank 1's run alone: exit 2 on every rank (it was 2 or 3, whichever rank
# stopped first), rank 1 naming the row, rank 0 pointing to it
cat > "$work/bad.toml" <<TOML
[sweep]
scenario = "$PWD/scenarios/geometry-A.toml"
set = ["release.scale=20", "stop.t_max=0.002", "stop.rest_duration=0.001", "output.snapshot_interval=0"]
[[rows]]
"output.track" = [1]
[[rows]]
"output.track" = [100000]
TOML
for attempt in 1 2 3; do
  rc=0
  "${mpi[@]}" "$exe" sweep "$work/bad.toml" --jobs 1 --out "$work/bad-$attempt" > "$work/bad.log" 2>&1 || rc=$?
  test "$rc" -eq 2 || { cat "$work/bad.log"; echo "bad input on one rank: exit $rc, not 2"; exit 1; }
done
grep -q 'rank 1 of 2.*row002-seed1.*output.track' "$work/bad.log"
# SIGTERM to the ranks (a batch system's stop): every rank writes its runs' checkpoints and
# stops with exit 4, and the same command resumes them to the same sweep.csv
cat > "$work/long.toml" <<TOML
[sweep]
scenario = "$PWD/scenarios/geometry-A.toml"
set = ["release.scale=20", "stop.t_max=1.5", "stop.rest_ke_fraction=1e-12", "output.snapshot_interval=0"]
[grid]
"material.friction_disc_deg" = [14, 15, 16]
TOML
"${mpi[@]}" "$exe" sweep "$work/long.toml" --jobs 1 --out "$work/long" > "$work/long.log" 2>&1 &
launcher=$!
n=0
while [ "$(ls "$work"/long/runs/*/release.csv 2>/dev/null | wc -l)" -lt 2 ] && [ $n -lt 2400 ]; do sleep 0.05; n=$((n + 1)); done
pkill -TERM -P "$launcher"
rc=0
wait "$launcher" || rc=$?
test "$rc" -eq 4 || { cat "$work/long.log"; echo "SIGTERM to the ranks: exit $rc, not 4"; exit 1; }
stopped=$(ls "$work"/long/runs/*/checkpoint.bin | wc -l)
test "$stopped" -ge 1
"${mpi[@]}" "$exe" sweep "$work/long.toml" --jobs 1 --out "$work/long" > "$work/long.log" 2>&1
test "$(grep -c 'resumed from its checkpoint' "$work/long.log")" -eq "$stopped"
"$exe" sweep "$work/long.toml" --jobs 1 --out "$work/long-one" > "$work/long-one.log"
# the same table but for the column `reused` (a run that finished before the signal is reused)
cmp <(cut -d, -f1-3,5- "$work/long/sweep.csv") <(cut -d, -f1-3,5- "$work/long-one/sweep.csv")
echo "mpi: the same calibration tables and sweep.csv on 1 and 2 ranks, resumed across rank counts without recomputing; \
one exit code on every rank; stopped ranks resumed from their checkpoints"
