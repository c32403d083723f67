#!/usr/bin/env python3
"""What stepping from Python costs: World.step(1000) called from a Python loop against the
same steps in one call (the C++ loop, World::run), on two worlds built from the same scenario,
timed in turn (A B, B A, ...) with the ratio pair by pair.

    PYTHONPATH=build/python /usr/bin/python3 bench/python_step.py [--scale 20] [--steps 100000] [--pairs 5]
"""
import argparse
import os
import statistics
import time

import demlab

ROOT = os.path.dirname(os.path.dirname(os.path.abspath(__file__)))


def main():
    ap = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    ap.add_argument("--scale", type=int, default=20)
    ap.add_argument("--steps", type=int, default=100000)
    ap.add_argument("--pairs", type=int, default=5)
    ap.add_argument("--threads", type=int, default=1)
    a = ap.parse_args()
    sc = demlab.load_scenario(os.path.join(ROOT, "scenarios", "geometry-A.toml"), {"release.scale": a.scale})
    ratios, loop_t, one_t = [], [], []
    n = None
    for _ in range(a.pairs):
        w1 = demlab.World.from_scenario(sc, threads=a.threads)
        w2 = demlab.World.from_scenario(sc, threads=a.threads)
        n = w1.disc_count
        def loop():
            t = time.perf_counter()
            for _ in range(a.steps // 1000):
                w1.step(1000)
            return time.perf_counter() - t

        def one():
            t = time.perf_counter()
            w2.step(a.steps // 1000 * 1000)
            return time.perf_counter() - t

        # A B, then B A in the next pair: neither always has the warmer cache
        if len(ratios) % 2 == 0:
            tl, to = loop(), one()
        else:
            to, tl = one(), loop()
        assert (w1.positions == w2.positions).all()  # the same steps, the same bits
        loop_t.append(tl)
        one_t.append(to)
        ratios.append(tl / to)
    print("geometry A, scale %d (%d discs), %d steps from t = 0, %d thread(s), %d pairs" % (
        a.scale, n, a.steps, a.threads, a.pairs))
    print("  step(1000) from a Python loop: median %.3f s" % statistics.median(loop_t))
    print("  one call (the C++ loop):       median %.3f s" % statistics.median(one_t))
    print("  ratio pair by pair: min %.4f, median %.4f, max %.4f" % (min(ratios), statistics.median(ratios), max(ratios)))


if __name__ == "__main__":
    main()
