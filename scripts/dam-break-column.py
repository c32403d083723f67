#!/usr/bin/env python3
"""The dam-break column's misfit against the thesis' PFC2D angles (Table 7, issue 49).

usage: scripts/dam-break-column.py SWEEP_DIR

Reads SWEEP_DIR/sweep.csv (sweeps/dam-break-column.toml) and data/dam_break_targets.csv; for
each column (dam_break.width x dam_break.height), floor friction and friction angle, the mean absolute
difference of gamma_1..gamma_5 and gamma_ges from the thesis' PFC2D run at that angle, and per
column the mean over the angles and its standard error over the seeds (each seed's misfit
averaged over the angles). Prints a
markdown table, the best column first.
"""
import csv
import os
import statistics
import sys

ROOT = os.path.dirname(os.path.dirname(os.path.abspath(__file__)))
KEYS = ["gamma_ges", "gamma_1", "gamma_2", "gamma_3", "gamma_4", "gamma_5"]


def targets():
    pfc = {}
    with open(os.path.join(ROOT, "data", "dam_break_targets.csv")) as f:
        rows = [r for r in csv.reader(line for line in f if not line.startswith("#"))]
    header = rows[0]
    for r in rows[1:]:
        for c, name in enumerate(header[2:], start=2):
            pfc.setdefault(float(name[3:]), {})[r[0]] = float(r[c])
    return pfc


def main():
    if len(sys.argv) != 2:
        sys.exit(__doc__)
    pfc = targets()
    with open(os.path.join(sys.argv[1], "sweep.csv")) as f:
        runs = list(csv.DictReader(f))
    by_column = {}
    for r in runs:
        width, height = float(r["dam_break.width"]), float(r["dam_break.height"])
        floor = (float(r.get("material.friction_wall_deg") or 21.7), r.get("material.friction_rule_disc_wall") or "max")
        angle = float(r["material.friction_disc_deg"])
        got = [r.get(k + "_deg", "") for k in KEYS]
        if angle not in pfc or any(g == "" for g in got):
            continue
        misfit = statistics.mean(abs(float(g) - pfc[angle][k]) for g, k in zip(got, KEYS))
        by_column.setdefault((width, height, floor), {}).setdefault(angle, {})[int(r["seed"])] = misfit
    rows = []
    for (w, h, floor), per_angle in by_column.items():
        means = {a: statistics.mean(m.values()) for a, m in per_angle.items()}
        # each seed's misfit over the angles, and their spread: the column's standard error
        seeds = sorted(set.intersection(*(set(m) for m in per_angle.values())))
        per_seed = [statistics.mean(per_angle[a][k] for a in per_angle) for k in seeds]
        error = statistics.stdev(per_seed) / len(per_seed) ** 0.5 if len(per_seed) > 1 else float("nan")
        rows.append((statistics.mean(means.values()), w, h, floor, means, error, len(per_seed)))
    angles = sorted({a for r in rows for a in r[4]})
    lines = ["| width (m) | height (m) | floor | " + " | ".join(f"{a:g} deg" for a in angles) + " | mean (deg) | standard error (seeds) |",
             "|---" * (len(angles) + 5) + "|"]

    def floor_name(f):
        deg, rule = f
        if rule == "max" and deg == 21.7:
            return "21.7 deg (measured)"
        if rule == "min" and deg == 0:
            return "0 (PFC's default wall)"
        if rule == "min" and deg >= 45:
            return "the discs'"
        return f"{deg:g} deg ({rule})"
    for mean, w, h, floor, means, error, n in sorted(rows):
        lines.append(f"| {w:g} | {h:g} | {floor_name(floor)} | " + " | ".join(f"{means[a]:.2f}" if a in means else "-" for a in angles)
                     + f" | {mean:.2f} | {error:.2f} ({n}) |")
    print("Mean |gamma - PFC2D gamma| over gamma_ges and gamma_1..5 (deg), per friction angle:\n")
    print("\n".join(lines))


if __name__ == "__main__":
    main()
