#!/usr/bin/env python3
"""A measurement of one's own from a stepping loop: the kinetic energy of the discs that have
passed the barrier's foot (x beyond W3's lower end) in geometry A at scale 20, sampled every
5 ms of simulated time, written to OUT/barrier_energy.csv and plotted to OUT/barrier_energy.png.

    PYTHONPATH=build/python /usr/bin/python3 examples/barrier_energy.py --out runs/barrier-energy
"""
import argparse
import os

import matplotlib

matplotlib.use("Agg")
import matplotlib.pyplot as plt  # noqa: E402
import numpy as np  # noqa: E402

import demlab  # noqa: E402

ROOT = os.path.dirname(os.path.dirname(os.path.abspath(__file__)))


def main():
    ap = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    ap.add_argument("--out", default="runs/barrier-energy")
    ap.add_argument("--t-max", type=float, default=2.0, help="simulated time, s")
    ap.add_argument("--scale", type=int, default=20)
    a = ap.parse_args()
    os.makedirs(a.out, exist_ok=True)
    sc = demlab.load_scenario(os.path.join(ROOT, "scenarios", "geometry-A.toml"), {"release.scale": a.scale})
    foot_x = sc["flume.w3_start"][0]  # m
    world = demlab.World.from_scenario(sc, threads=2)
    rows = []
    next_sample = 0.0
    while world.time < a.t_max:
        if world.time >= next_sample:
            x = world.positions[:, 0]
            past = x > foot_x
            v2 = np.sum(world.velocities[past] ** 2, axis=1)
            ke = 0.5 * float(np.sum(world.masses[past] * v2))  # J per m of thickness
            rows.append((world.time, int(past.sum()), ke, world.kinetic_energy(), world.wall_forces()[2, 0]))
            next_sample += 0.005
        world.step(50)
    rows = np.array(rows)
    csv = os.path.join(a.out, "barrier_energy.csv")
    np.savetxt(csv, rows, delimiter=",", comments="",
               header="t_s,discs_past_foot,ke_past_foot_J_per_m,ke_all_J_per_m,fx_barrier_N_per_m")
    fig, ax = plt.subplots(figsize=(7, 4))
    ax.plot(rows[:, 0], rows[:, 3], label="all discs")
    ax.plot(rows[:, 0], rows[:, 2], label="past the barrier's foot")
    ax.set_xlabel("t (s)")
    ax.set_ylabel("kinetic energy (J/m)")
    ax.set_title("geometry A, scale %d" % a.scale)
    ax.legend()
    fig.tight_layout()
    png = os.path.join(a.out, "barrier_energy.png")
    fig.savefig(png, dpi=100)
    i = int(np.argmax(rows[:, 2]))
    print("%d steps to t = %.3f s; the discs past the foot carry at most %.2f J/m (%d discs) at t = %.3f s" % (
        world.step_count, world.time, rows[i, 2], rows[i, 1], rows[i, 0]))
    print("wrote", csv, "and", png)


if __name__ == "__main__":
    main()
