#!/usr/bin/env python3
"""The barrier-load study (docs/barrier-loads.md): geometry A's loads on the barrier as a
designer reads them (summary.json's every-step, filtered and static loads, the impact's
impulse, the approaching flow and the design coefficients), over the contact stiffness and
over release masses.

usage: scripts/barrier-loads-study.py OUT_DIR [--part stiffness,masses] [--threads 2] [--demlab build/demlab]

  stiffness: kn = ks of discs and walls 1e7, 1e8 (the thesis') and 1e9 N/m at scale 8, the
             walls' alone 1e7 and 1e9 at scale 8, and the three discs-and-walls stiffnesses
             again at scale 4 (each run settles its own release mass: the same seed).
  masses:    scale 4, scenario.seed 1, 2 and 3 (three release masses), Models 1, 2 and 3 of
             each from the same settled mass (--release-from the seed's Model 3 run).

Finished runs are kept: rerunning the same command runs only what is missing. The tables go
to OUT_DIR/study.md (markdown, as docs/barrier-loads.md shows them).
"""
import argparse
import csv
import json
import os
import statistics
import subprocess
import sys

ROOT = os.path.dirname(os.path.dirname(os.path.abspath(__file__)))
SCENARIO = os.path.join(ROOT, "scenarios", "geometry-A.toml")


def run(demlab, out, name, sets, threads, release=None):
    folder = os.path.join(out, name)
    if os.path.exists(os.path.join(folder, "summary.json")):
        return folder
    cmd = [demlab, "run", SCENARIO, "--out", folder, "--force", "--no-plots", "--threads", str(threads),
           "--set", "output.snapshot_interval=0"]
    for s in sets:
        cmd += ["--set", s]
    if release:
        cmd += ["--release-from", release]
    print(" ".join(cmd), flush=True)
    with open(folder + ".log", "w") as log:
        if subprocess.call(cmd, stdout=log, stderr=subprocess.STDOUT) != 0:
            sys.exit(f"{name} failed: see {folder}.log")
    return folder


def summary(folder):
    with open(os.path.join(folder, "summary.json")) as f:
        s = json.load(f)
    # the impact ratio: the largest filtered load within 0.3 s of the front's arrival over the
    # static load (forces.csv's filtered column)
    s["impact_ratio"] = None
    if s.get("approach_froude") is None and s.get("approach_depth"):
        s["approach_froude"] = s["approach_speed"] / (9.81 * s["approach_depth"]) ** 0.5
    t0, static = s.get("t_front_at_barrier"), s.get("static_fx_barrier")
    if t0 is not None and static:
        with open(os.path.join(folder, "forces.csv")) as f:
            peak = max((abs(float(r["fx_barrier_filtered_N_per_m"])) for r in csv.DictReader(f)
                        if r["fx_barrier_filtered_N_per_m"] and t0 <= float(r["t_s"]) <= t0 + 0.3), default=None)
        if peak is not None:
            s["impact_ratio"] = peak / static
    return s


def cell(v, fmt):
    return "-" if v is None else format(v, fmt)


COLUMNS = [  # key, header, format
    ("t_front_at_barrier", "front at barrier (s)", ".3f"),
    ("peak_fx_barrier", "every-step peak (N/m)", ".0f"),
    ("t_peak_fx_barrier", "at (s)", ".3f"),
    ("peak_fx_barrier_filtered", "filtered peak (N/m)", ".0f"),
    ("t_peak_fx_barrier_filtered", "at (s)", ".3f"),
    ("static_fx_barrier", "static (N/m)", ".0f"),
    ("impact_ratio", "impact ratio", ".2f"),
    ("impact_ix_barrier", "impact impulse (N s/m)", ".1f"),
    ("t_barrier_load_steady", "steady from (s)", ".2f"),
    ("approach_depth", "h (m)", ".3f"),
    ("approach_speed", "v (m/s)", ".2f"),
    ("approach_froude", "Fr", ".1f"),
    ("impact_coefficient_alpha", "alpha", ".2f"),
    ("static_coefficient_k", "K", ".2f"),
    ("runout_s", "run-out (m)", ".3f"),
]


WINDOWS = (0.005, 0.01, 0.02, 0.05, 0.1, 0.2)  # s


def windowed_peaks(folder):
    """The largest mean x-force on the barrier over each window W, from forces.csv's impulse
    (summed every step, so a difference over rows is the exact mean force between them; the
    windows are whole numbers of the 5 ms rows)."""
    with open(os.path.join(folder, "forces.csv")) as f:
        rows = [(float(r["t_s"]), float(r["ix_barrier_Ns_per_m"])) for r in csv.DictReader(f)]
    dt = rows[1][0] - rows[0][0]
    out = {}
    for w in WINDOWS:
        lag = max(1, round(w / dt))
        out[w] = max(abs(rows[k][1] - rows[k - lag][1]) / (rows[k][0] - rows[k - lag][0]) for k in range(lag, len(rows)))
    return out


def table(rows):
    lines = ["| run | " + " | ".join(h for _, h, _ in COLUMNS) + " |", "|---" * (len(COLUMNS) + 1) + "|"]
    for name, s in rows:
        lines.append(f"| {name} | " + " | ".join(cell(s.get(k), f) for k, _, f in COLUMNS) + " |")
    return lines


def main():
    ap = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    ap.add_argument("out")
    ap.add_argument("--part", default="stiffness,masses")
    ap.add_argument("--threads", type=int, default=2)
    ap.add_argument("--demlab", default=os.path.join(ROOT, "build", "demlab"))
    a = ap.parse_args()
    os.makedirs(a.out, exist_ok=True)
    md = []
    parts = a.part.split(",")
    if "stiffness" in parts:
        rows, folders = [], []
        for scale, cases in ((8, [("1e7", "1e7", "1e7"), ("1e8", "1e8", "1e8"), ("1e9", "1e9", "1e9"),
                                  ("walls 1e7", "1e8", "1e7"), ("walls 1e9", "1e8", "1e9")]),
                             (4, [("1e7", "1e7", "1e7"), ("1e8", "1e8", "1e8"), ("1e9", "1e9", "1e9")])):
            for label, k_disc, k_wall in cases:
                name = f"k-s{scale}-{label.replace(' ', '-')}"
                sets = [f"release.scale={scale}", f"material.kn={k_disc}", f"material.ks={k_disc}",
                        f"material.wall_kn={k_wall}", f"material.wall_ks={k_wall}"]
                folder = run(a.demlab, a.out, name, sets, a.threads)
                rows.append((f"scale {scale}, k {label}", summary(folder)))
                folders.append((f"scale {scale}, k {label}", folder))
        md += ["## Contact stiffness (geometry A, Model 3)", ""] + table(rows) + [""]
        md += ["## The barrier's largest mean x-force over a window W (N/m), by stiffness", "",
               "| run | every step | " + " | ".join(f"W = {w * 1000:g} ms" for w in WINDOWS) + " |",
               "|---" * (len(WINDOWS) + 2) + "|"]
        for name, folder in folders:
            p = windowed_peaks(folder)
            md.append(f"| {name} | {summary(folder)['peak_fx_barrier']:.0f} | " + " | ".join(f"{p[w]:.0f}" for w in WINDOWS) + " |")
        md.append("")
    if "masses" in parts:
        rows, by_model = [], {}
        for seed in (1, 2, 3):
            ref = run(a.demlab, a.out, f"m3-seed{seed}", [f"scenario.seed={seed}", "release.scale=4"], a.threads)
            for model in (1, 2, 3):
                folder = ref if model == 3 else run(a.demlab, a.out, f"m{model}-seed{seed}",
                                                    [f"scenario.seed={seed}", "release.scale=4", f"rotation.model={model}"],
                                                    a.threads, os.path.join(ref, "release.csv"))
                s = summary(folder)
                rows.append((f"Model {model}, seed {seed}", s))
                by_model.setdefault(model, []).append(s)
        md += ["## Release masses (geometry A, scale 4)", ""] + table(rows) + [""]
        md += ["| Model | " + " | ".join(h for _, h, _ in COLUMNS) + " |", "|---" * (len(COLUMNS) + 1) + "|"]
        for model, ss in sorted(by_model.items()):
            cells = []
            for k, _, f in COLUMNS:
                v = [s[k] for s in ss if s.get(k) is not None]
                cells.append("-" if not v else f"{format(statistics.mean(v), f)} ± {format(statistics.stdev(v) if len(v) > 1 else 0.0, f)}")
            md.append(f"| {model} (mean ± std of {len(ss)}) | " + " | ".join(cells) + " |")
        md.append("")
    with open(os.path.join(a.out, "study.md"), "w") as f:
        f.write("\n".join(md) + "\n")
    print("\n".join(md))


if __name__ == "__main__":
    main()
