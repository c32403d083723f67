#!/usr/bin/env bash
# Regenerates the figures the README shows (figures/*.png) from runs of geometries A, B, C
# and of the snow slide with and without bonds, the Attabad-like section by DEBRIS, and
# geometry A by DEM against DAN.
# usage: scripts/make-figures.sh [RUNS_DIR]     (default runs/figures; SCALE=4 by default)
# Runs that already exist in RUNS_DIR (with a summary.json) are reused, not recomputed.
# At scale 4 the three runs take about an hour on 2 cores; SCALE=20 gives a quick look.
set -euo pipefail
cd "$(dirname "$0")/.."
runs="${1:-runs/figures}"
scale="${SCALE:-4}"
demlab=./build/demlab
[ -x "$demlab" ] || { echo "build demlab first (scripts/main-job.sh or scripts/test.sh)"; exit 1; }
mkdir -p "$runs" figures
pids=()
for g in A B C; do
  out="$runs/geometry-$g-s$scale"
  if [ ! -f "$out/summary.json" ]; then
    rm -rf "$out"
    "$demlab" run "scenarios/geometry-$g.toml" --scale "$scale" --out "$out" --no-plots > "$out.log" 2>&1 &
    pids+=($!)
    # two cores: at most two runs at once
    if [ ${#pids[@]} -ge 2 ]; then wait "${pids[0]}"; pids=("${pids[@]:1}"); fi
  fi
done
for p in "${pids[@]}"; do wait "$p"; done
a="$runs/geometry-A-s$scale"
"$demlab" render "$a" --every 0.2 --size 480x270 --out "$a/strip" --force --strip figures/geometry-A-strip.png
for g in A B C; do
  r="$runs/geometry-$g-s$scale"
  "$demlab" render "$r" --last --view barrier --size 640x360 --out "$r/deposit" --force --strip "figures/deposit-$g.png"
done
# the snow slab with and without bonds (seconds, not an hour): the bonded slab by its bonds
# (intact blue, lost orange to red), the loose one by its rows
for v in bonded loose; do
  r="$runs/snow-slide-$v"
  if [ "$v" = bonded ]; then set_bonds=(); color=bonds; else set_bonds=(--set cohesion.enabled=false); color=layers; fi
  [ -f "$r/summary.json" ] || { rm -rf "$r"; "$demlab" run scenarios/snow-slide-2d.toml "${set_bonds[@]}" --out "$r" --no-plots > "$r.log" 2>&1; }
  "$demlab" render "$r" --every 4 --color "$color" --view=-50,-1,40,32 --size 960x352 --out "$r/strip" --force \
    --strip "figures/snow-slide-$v.png"
done
# the Attabad-like section by DEBRIS to 300 s (about a minute): every 30 s by speed, and the
# deposit thickness along the section
r="$runs/attabad-2d"
[ -f "$r/summary.json" ] || { rm -rf "$r"; "$demlab" run scenarios/attabad-2d.toml --out "$r" --no-plots > "$r.log" 2>&1; }
"$demlab" render "$r" --every 30 --size 480x270 --view=-450,-50,1950,1350 --color speed --speed-max 15 \
  --out "$r/strip" --force --strip figures/attabad-2d-strip.png
gnuplot -e "set terminal pngcairo size 800,360; set output 'figures/attabad-2d-deposit.png'; set datafile separator ','; \
  set key off; set grid; set xlabel 'distance along the section s (m)'; set ylabel 'deposit thickness normal to the bed (m)'; \
  set title 'attabad-2d at t = 300 s (still moving): deposit thickness, 10 m bins'; \
  plot '$r/deposit.csv' every ::1 using 1:2 with steps lw 2"
# geometry A by DEM and by DAN (synchronised at 0.4 s on the DEM front, as the thesis' Abb. 37)
d="$runs/geometry-A-dan"
"$demlab" run scenarios/geometry-A.toml --solver dan --set "dan.sync_front=\"$(realpath "$a")/front.csv\"" --out "$d" --force --no-plots > "$d.log"
"$demlab" compare "$a" "$d" --out "$runs/compare-A" --force > /dev/null
cp "$runs/compare-A/front.png" figures/compare-A-front.png
cp "$runs/compare-A/deposit.png" figures/compare-A-deposit.png
"$demlab" plot "$a" > /dev/null
cp "$a/plots/forces_x.png" figures/geometry-A-forces-x.png
cp "$a/plots/forces_y.png" figures/geometry-A-forces-y.png
du -sh figures
