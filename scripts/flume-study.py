#!/usr/bin/env python3
"""The flume sensitivity study (docs/flume.md): geometry A run with one modelling choice
changed at a time, all from the same settled release mass, and the barrier-force landmarks of
the thesis (section 7.2) read off each run.

usage: scripts/flume-study.py OUT_DIR [--scale 8] [--jobs 1] [--only NAME,...] [--seeds 2,3] [--plot NAME,...]

OUT_DIR/release/ is the reference run (the defaults); its release.csv is reused by every
variant (--release-from), so the variants differ only in the choice they change. With
--seeds, the reference and the variants named by --only are run again from the release masses
of other seeds (scenario.seed), for the spread of one mass against another. Finished runs are
kept: rerunning the same command runs only what is missing. The table goes to OUT_DIR/study.md
and OUT_DIR/study.csv, the barrier force curves to OUT_DIR/fx_barrier.png and
OUT_DIR/fy_arc.png (gnuplot).
"""
import argparse
import concurrent.futures
import csv
import json
import os
import subprocess
import sys

ROOT = os.path.dirname(os.path.dirname(os.path.abspath(__file__)))
DEMLAB = os.path.join(ROOT, "build", "demlab")
SCENARIO = os.path.join(ROOT, "scenarios", "geometry-A.toml")

# name, overrides, what it tests. The reference is the shipped scenario (Model 3, Variant II,
# dp_mode 3, beta_n = beta_s = 0.5, mu_Br 0.5 per disc, literal rolling resistance, wall
# friction max, no local damping during the flow).
VARIANTS = [
    ("reference", [], "the shipped defaults"),
    ("dp0", ["damping.dp_mode=\"0\""], "PFC's default dashpot mode: both dashpots always"),
    ("dp1", ["damping.dp_mode=\"1\""], "no tensile normal force, shear dashpot always"),
    ("dp2", ["damping.dp_mode=\"2\""], "no shear dashpot while sliding, tension allowed"),
    ("beta_s0", ["damping.beta_s=0.0"], "no shear dashpot"),
    ("beta_s0.2", ["damping.beta_s=0.2"], "a weaker shear dashpot"),
    ("beta_n0.2", ["damping.beta_n=0.2"], "a weaker normal dashpot (restitution 0.53 against 0.16)"),
    ("mubr_contact", ["rotation.damping_per=\"contact\""], "mu_Br once per contact and step"),
    ("mubr0.05", ["rotation.mu_br=0.05"], "mu_Br 0.05: the spin cut to 5 % each step (stronger)"),
    ("mubr0.9", ["rotation.mu_br=0.9"], "mu_Br 0.9 each step (weaker)"),
    ("mubr0.99", ["rotation.mu_br=0.99"], "mu_Br 0.99 each step"),
    ("mubr0.9931", ["rotation.mu_br=0.9931"], "mu_Br 0.5 once per 100 steps (0.5^(1/100) = 0.9931 each step)"),
    ("mubr0.99931", ["rotation.mu_br=0.99931"], "mu_Br 0.5 once per 1,000 steps"),
    ("rolling_nf", ["rotation.rolling_form=\"normal_force\""], "eq. 2.71 with the wall's normal force"),
    ("model2", ["rotation.model=2"], "Model 2: no rotational damping inside the mass"),
    ("model1", ["rotation.model=1"], "Model 1: rotation locked"),
    ("variantI", ["release.variant=\"I\""], "Variant I: the gate deleted at t = 0"),
    ("wall_min", ["material.friction_rule_disc_wall=\"min\""], "disc-wall friction the smaller coefficient"),
    ("local0.1", ["damping.local_alpha=0.1"], "PFC local damping 0.1 during the flow"),
    ("local0.7", ["damping.local_alpha=0.7"], "PFC local damping 0.7 (PFC's default) during the flow"),
    ("dp0_variantI", ["damping.dp_mode=\"0\"", "release.variant=\"I\""], "pair: dp_mode 0, Variant I"),
    ("dp1_variantI", ["damping.dp_mode=\"1\"", "release.variant=\"I\""], "pair: dp_mode 1, Variant I"),
    ("dp1_model1", ["damping.dp_mode=\"1\"", "rotation.model=1"], "pair: dp_mode 1, Model 1"),
    ("model2_dp2", ["rotation.model=2", "damping.dp_mode=\"2\""], "pair: Model 2, dp_mode 2"),
    ("wall_min_model1", ["material.friction_rule_disc_wall=\"min\"", "rotation.model=1"], "Model 1 beside wall_min"),
]

THESIS = {"t_front_at_barrier": 0.8, "t_peak_fx_barrier": 0.8, "t_peak_fy_arc": 0.7, "t_steady": 1.4}


def read_series(path):
    with open(path, newline="") as f:
        rows = list(csv.reader(f))
    head = rows[0]
    cols = {h: [] for h in head}
    for r in rows[1:]:
        for h, v in zip(head, r):
            cols[h].append(float(v))
    return cols


def smoothed(t, y, window):
    """centred moving mean over `window` seconds"""
    out, n = [], len(t)
    for i in range(n):
        lo, hi = i, i
        while lo > 0 and t[i] - t[lo - 1] <= window / 2:
            lo -= 1
        while hi < n - 1 and t[hi + 1] - t[i] <= window / 2:
            hi += 1
        out.append(sum(y[lo:hi + 1]) / (hi - lo + 1))
    return out


def landmarks(run):
    with open(os.path.join(run, "summary.json")) as f:
        s = json.load(f)
    fc = read_series(os.path.join(run, "forces.csv"))
    t, fx, fy = fc["t_s"], fc["fx_barrier_N_per_m"], fc["fy_arc_N_per_m"]
    fxs, fys = smoothed(t, [abs(v) for v in fx], 0.05), smoothed(t, [abs(v) for v in fy], 0.05)
    imax = max(range(len(t)), key=lambda i: fxs[i])
    jmax = max(range(len(t)), key=lambda i: fys[i])
    final_fx = sum(fx[-20:]) / len(fx[-20:])
    tf = s["t_front_at_barrier"]
    # the impact: the largest smoothed barrier force within 0.2 s of the front's arrival,
    # over the final (static) load; above 1 the barrier saw a peak before the deposit built up
    win = [fxs[i] for i in range(len(t)) if tf <= t[i] <= tf + 0.2]
    impact = max(win) / final_fx if win and final_fx > 0 else float("nan")
    ty = fc["fy_total_N_per_m"]
    final_fy = ty[-1]
    steady = t[-1]
    for i in range(len(t) - 1, -1, -1):
        if abs(ty[i] - final_fy) > 0.05 * abs(final_fy):
            steady = t[min(i + 1, len(t) - 1)]
            break
    return {
        "t_front_at_barrier": tf,
        "t_peak_fx_barrier": s["t_peak_fx_barrier"],
        "t_peak_fx_barrier_smoothed": t[imax],
        "t_peak_fy_arc": s["t_peak_fy_arc"],
        "t_peak_fy_arc_smoothed": t[jmax],
        "impact_over_static": impact,
        "t_steady": steady,
        "t_end": s["t_end"],
        "stop_reason": s["stop_reason"],
        "runup_height": s["runup_height"],
        "runout_s": s["runout_s"],
        "energy_balance_error": s["energy_balance_error"],
    }


def run_one(out, name, sets, release, scale, seed):
    folder = os.path.join(out, name)
    if os.path.exists(os.path.join(folder, "summary.json")):
        return folder, "kept"
    cmd = [DEMLAB, "run", SCENARIO, "--scale", str(scale), "--out", folder, "--no-plots", "--force"]
    if release:
        cmd += ["--release-from", release]
    if seed is not None:
        cmd += ["--set", "scenario.seed=%d" % seed]
    for s in sets:
        cmd += ["--set", s]
    with open(folder + ".log", "w") as log:
        rc = subprocess.call(cmd, stdout=log, stderr=subprocess.STDOUT)
    if rc != 0:
        raise SystemExit("%s failed (exit code %d): see %s.log" % (name, rc, folder))
    return folder, "ran"


def overlay(out, names, column, png, title):
    """the 50 ms means of one force column of every run, one curve each"""
    script = ["set terminal pngcairo size 1100,650 noenhanced", "set output '%s'" % png, "set key outside right",
              "set xlabel 't (s)'", "set ylabel '%s, 50 ms mean'" % column, "set title '%s'" % title,
              "set xrange [0.5:2.5]", "set grid"]
    plots = []
    for n in names:
        fc = read_series(os.path.join(out, n, "forces.csv"))
        dat = os.path.join(out, n, column + "_50ms.dat")
        with open(dat, "w") as f:
            for t, y in zip(fc["t_s"], smoothed(fc["t_s"], [abs(v) for v in fc[column]], 0.05)):
                f.write("%.4f %.6g\n" % (t, y))
        plots.append("'%s' using 1:2 with lines title '%s'" % (dat, n))
    script.append("plot " + ", ".join(plots))
    subprocess.run(["gnuplot"], input="\n".join(script), text=True, check=True)


def main():
    ap = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    ap.add_argument("out")
    ap.add_argument("--scale", type=int, default=8)
    ap.add_argument("--jobs", type=int, default=1)
    ap.add_argument("--only", default="", help="comma-separated variant names (default: all)")
    ap.add_argument("--seeds", default="", help="comma-separated further seeds for the reference and --only")
    ap.add_argument("--plot", default="", help="comma-separated variants to overlay (default: all in the table)")
    a = ap.parse_args()
    os.makedirs(a.out, exist_ok=True)
    chosen = [v for v in VARIANTS if not a.only or v[0] in a.only.split(",") or v[0] == "reference"]
    # the reference first: its release mass is every variant's
    run_one(a.out, "reference", [], None, a.scale, None)
    release = os.path.join(a.out, "reference", "release.csv")
    jobs = [(v[0], v[1], release, None) for v in chosen if v[0] != "reference"]
    for seed in [int(x) for x in a.seeds.split(",") if x]:
        run_one(a.out, "reference-seed%d" % seed, [], None, a.scale, seed)
        rel = os.path.join(a.out, "reference-seed%d" % seed, "release.csv")
        jobs += [("%s-seed%d" % (v[0], seed), v[1], rel, None) for v in chosen if v[0] != "reference"]
    with concurrent.futures.ThreadPoolExecutor(a.jobs) as pool:
        futs = [pool.submit(run_one, a.out, n, s, r, a.scale, sd) for n, s, r, sd in jobs]
        for f in concurrent.futures.as_completed(futs):
            folder, how = f.result()
            print("%s: %s" % (os.path.basename(folder), how), flush=True)

    names = ["reference"] + [j[0] for j in jobs if not j[0].startswith("reference")]
    names += ["reference-seed%s" % x for x in a.seeds.split(",") if x]
    what = {v[0]: (v[1], v[2]) for v in VARIANTS}
    rows = []
    for n in names:
        base = n.split("-seed")[0]
        lm = landmarks(os.path.join(a.out, n))
        lm["variant"] = n
        lm["overrides"] = " ".join(what[base][0])
        lm["what"] = what[base][1]
        rows.append(lm)
    keys = ["variant", "t_front_at_barrier", "t_peak_fx_barrier", "t_peak_fx_barrier_smoothed", "t_peak_fy_arc",
            "t_peak_fy_arc_smoothed", "impact_over_static", "t_steady", "t_end", "stop_reason", "runup_height",
            "runout_s", "energy_balance_error", "overrides", "what"]
    with open(os.path.join(a.out, "study.csv"), "w", newline="") as f:
        w = csv.DictWriter(f, fieldnames=keys)
        w.writeheader()
        w.writerows(rows)
    with open(os.path.join(a.out, "study.md"), "w") as f:
        f.write("| variant | front at barrier (s) | peak fx barrier raw / 50 ms (s) | peak fy arc raw / 50 ms (s) "
                "| impact / static fx | steady from (s) | rest (s) | run-up (m) | run-out s (m) | what |\n")
        f.write("|---|---|---|---|---|---|---|---|---|---|\n")
        f.write("| thesis | 0.8 | 0.8 | 0.7 | > 1 | 1.4 | | M1 about 0.08 beyond the lab; M3 not above M1 | | |\n")
        for r in rows:
            f.write("| %s | %.3f | %.3f / %.3f | %.3f / %.3f | %.2f | %.2f | %.2f%s | %.3f | %.3f | %s |\n" % (
                r["variant"], r["t_front_at_barrier"], r["t_peak_fx_barrier"], r["t_peak_fx_barrier_smoothed"],
                r["t_peak_fy_arc"], r["t_peak_fy_arc_smoothed"], r["impact_over_static"], r["t_steady"], r["t_end"],
                "" if r["stop_reason"] == "rest" else " (" + r["stop_reason"] + ")", r["runup_height"],
                r["runout_s"], r["what"]))
    if subprocess.call(["which", "gnuplot"], stdout=subprocess.DEVNULL) == 0:
        if a.plot:
            names = [n for n in a.plot.split(",") if os.path.isdir(os.path.join(a.out, n))]
        overlay(a.out, names, "fx_barrier_N_per_m", os.path.join(a.out, "fx_barrier.png"), "x-force on the barrier W3")
        overlay(a.out, names, "fy_arc_N_per_m", os.path.join(a.out, "fy_arc.png"), "y-force on the arc W2")
    print(open(os.path.join(a.out, "study.md")).read())


if __name__ == "__main__":
    sys.exit(main())
