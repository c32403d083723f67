#!/usr/bin/env python3
"""A friction sweep from Python: geometry A at scale 20 (364 discs, seconds a run) with three
disc friction angles, all from the same settled release mass, and the run-out plotted against
the angle (matplotlib, to OUT/runout.png).

    PYTHONPATH=build/python /usr/bin/python3 examples/friction_sweep.py --out runs/friction-sweep
"""
import argparse
import os

import matplotlib

matplotlib.use("Agg")
import matplotlib.pyplot as plt  # noqa: E402

import demlab  # noqa: E402

ROOT = os.path.dirname(os.path.dirname(os.path.abspath(__file__)))


def main():
    ap = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    ap.add_argument("--out", default="runs/friction-sweep")
    ap.add_argument("--angles", default="12,15.5,19", help="disc friction angles, deg")
    ap.add_argument("--scale", type=int, default=20)
    a = ap.parse_args()
    angles = [float(x) for x in a.angles.split(",")]
    os.makedirs(a.out, exist_ok=True)
    base = demlab.load_scenario(os.path.join(ROOT, "scenarios", "geometry-A.toml"), {"release.scale": a.scale})
    release = None
    runout, runup = [], []
    for angle in angles:
        sc = base.with_overrides({"material.friction_disc_deg": angle})
        if release:
            sc = demlab.load_scenario(sc.path, sc.overrides, release_from=release)
        folder = demlab.run(sc, os.path.join(a.out, "phi-%g" % angle), threads=2, plots=False, force=True)
        # the first run's settled mass is every run's start, so only the angle differs
        release = release or os.path.join(folder.path, "release.csv")
        s = folder.summary
        runout.append(s["runout_s"])
        runup.append(s["runup_height"])
        print("phi_disc = %5.2f deg: run-out s = %.3f m, run-up %.3f m, at rest %.2f s (%s)" % (
            angle, s["runout_s"], s["runup_height"], s["t_end"], s["stop_reason"]))
    fig, ax = plt.subplots(figsize=(6, 4))
    ax.plot(angles, runout, "o-", label="run-out s (deposit front along the path)")
    ax.axhline(1.764, ls=":", color="grey", label="barrier foot, s = 1.764 m")
    ax.set_xlabel("disc friction angle (deg)")
    ax.set_ylabel("s (m)")
    ax.set_title("geometry A, scale %d: run-out against friction" % a.scale)
    ax.legend(fontsize=8)
    fig.tight_layout()
    png = os.path.join(a.out, "runout.png")
    fig.savefig(png, dpi=100)
    print("wrote", png)


if __name__ == "__main__":
    main()
