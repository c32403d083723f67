#!/usr/bin/env python3
"""The dam-break column's misfit against the thesis' PFC2D angles (Table 7, issue 49).

usage: scripts/dam-break-column.py SWEEP_DIR [--starts 0,0.1,0.2]

Reads SWEEP_DIR/sweep.csv (sweeps/dam-break-column.toml, sweeps/dam-break-sections.toml) and
data/dam_break_targets.csv; for each column (dam_break.width x dam_break.height), floor friction
and friction angle, the mean absolute difference of gamma_1..gamma_5 and gamma_ges from the
thesis' PFC2D run at that angle, and per column the mean over the angles and its standard error
over the seeds (each seed's misfit averaged over the angles). Prints a markdown table, the best
column first.

With --starts, each run's envelope.csv is measured again with the five sections beginning at
each of these distances from the back wall (dam_break.sections_start: the same least-squares
lines through the envelope's 1 mm samples, gamma_ges from the surface at the start to the toe),
and the start is a fourth unknown of the table.
"""
import csv
import math
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


def fitted_angle(env, lo, hi):
    """deg, the least-squares line's descent through the envelope samples in [lo, hi] (deposit.cpp)"""
    pts = [(x, y) for x, y in env if lo <= x <= hi]
    n = len(pts)
    sx, sy = sum(p[0] for p in pts), sum(p[1] for p in pts)
    sxx, sxy = sum(p[0] * p[0] for p in pts), sum(p[0] * p[1] for p in pts)
    den = n * sxx - sx * sx
    if n < 3 or not den > 0:
        return float("nan")
    return math.degrees(math.atan(-(n * sxy - sx * sy) / den))


def angles_from(envelope_csv, start):
    with open(envelope_csv) as f:
        env = [(float(a), float(b)) for a, b in list(csv.reader(f))[1:]]
    toe = env[-1][0]
    # past the toe the surface is the floor, y = 0 (deposit.cpp), on the same 1 mm samples
    floor = [((k + 1) * 0.001 + toe, 0.0) for k in range(int(round((start + 0.5 - toe) / 0.001)) + 1)]
    surface = env + floor
    got = {f"gamma_{i}": fitted_angle(surface, start + (5 - i) * 0.1 - 1e-9, start + (6 - i) * 0.1 + 1e-9) for i in range(1, 6)}
    top = next(((x, y) for x, y in env if x >= start - 1e-9), None)
    got["gamma_ges"] = math.degrees(math.atan(top[1] / max(toe - start, 1e-9))) if top else float("nan")
    return got


def main():
    args = sys.argv[1:]
    starts = None
    if len(args) == 3 and args[1] == "--starts":
        starts = [float(v) for v in args[2].split(",")]
        args = args[:1]
    if len(args) != 1:
        sys.exit(__doc__)
    pfc = targets()
    with open(os.path.join(args[0], "sweep.csv")) as f:
        runs = list(csv.DictReader(f))
    by_column = {}
    for r in runs:
        width = float(r.get("dam_break.width") or 0.2)
        height = float(r.get("dam_break.height") or 0.4)
        floor = (float(r.get("material.friction_wall_deg") or 21.7), r.get("material.friction_rule_disc_wall") or "max")
        angle = float(r["material.friction_disc_deg"])
        if angle not in pfc:
            continue
        for start in starts or [None]:
            if start is None:
                got = [r.get(k + "_deg", "") for k in KEYS]
                if any(g == "" for g in got):
                    continue
                got = [float(g) for g in got]
            else:
                measured = angles_from(os.path.join(args[0], "runs", r["run"], "envelope.csv"), start)
                got = [measured[k] for k in KEYS]
            if any(math.isnan(g) for g in got):
                continue
            misfit = statistics.mean(abs(g - pfc[angle][k]) for g, k in zip(got, KEYS))
            column = (width, height, floor) if start is None else (width, height, floor, start)
            by_column.setdefault(column, {}).setdefault(angle, {})[int(r["seed"])] = misfit
    rows = []
    for column, per_angle in by_column.items():
        w, h, floor = column[:3]
        start = column[3] if len(column) > 3 else None
        means = {a: statistics.mean(m.values()) for a, m in per_angle.items()}
        # each seed's misfit over the angles, and their spread: the column's standard error
        seeds = sorted(set.intersection(*(set(m) for m in per_angle.values())))
        per_seed = [statistics.mean(per_angle[a][k] for a in per_angle) for k in seeds]
        error = statistics.stdev(per_seed) / len(per_seed) ** 0.5 if len(per_seed) > 1 else float("nan")
        rows.append((statistics.mean(means.values()), w, h, floor, means, error, len(per_seed), start))
    angles = sorted({a for r in rows for a in r[4]})
    with_start = starts is not None
    lines = ["| width (m) | height (m) | floor | " + ("sections from (m) | " if with_start else "")
             + " | ".join(f"{a:g} deg" for a in angles) + " | mean (deg) | standard error (seeds) |",
             "|---" * (len(angles) + 5 + with_start) + "|"]

    def floor_name(f):
        deg, rule = f
        if rule == "max" and deg == 21.7:
            return "21.7 deg (measured)"
        if rule == "min" and deg == 0:
            return "0 (PFC's default wall)"
        if rule == "min" and deg >= 45:
            return "the discs'"
        return f"{deg:g} deg ({rule})"
    for mean, w, h, floor, means, error, n, start in sorted(rows, key=lambda r: r[0]):
        lines.append(f"| {w:g} | {h:g} | {floor_name(floor)} | " + (f"{start:g} | " if with_start else "") + " | ".join(f"{means[a]:.2f}" if a in means else "-" for a in angles)
                     + f" | {mean:.2f} | {error:.2f} ({n}) |")
    print("Mean |gamma - PFC2D gamma| over gamma_ges and gamma_1..5 (deg), per friction angle:\n")
    print("\n".join(lines))


if __name__ == "__main__":
    main()
