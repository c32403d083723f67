#!/usr/bin/env python3
"""The slope of scenarios/snow-slide-3d.toml, as an ESRI ASCII grid.

usage: scripts/snow-slope.py [OUT_DIR]    (default data/snow-slope-3d)

Writes bed.asc: a slope falling towards +x, shaped after com5SnowSlide's premises (release
slopes of about 28 to 50 degrees, a height difference of 30 m to 60-80 m): 35 degrees for 60 m
(the release lies on it), a convex break to 45 degrees for 15 m, a concave break to a 4-degree
run-out, and across it at x = 116-127 m a dam 4 m high (45-degree faces, a 3 m crest). Across
the slope (y) a shallow trough, 0.01 (y - 20)^2 m, keeps the slide near the middle. Grid cells
of 1 m, 151 x 41 nodes. Constructed, not surveyed; reproducible (no random numbers).
"""
import math
import os
import sys

ROOT = os.path.dirname(os.path.dirname(os.path.abspath(__file__)))
CELL = 1.0
NX, NY = 151, 41


def profile(x):
    """m, the slope's height along x (the trough's axis)."""
    t35, t45, t4 = math.tan(math.radians(35)), math.tan(math.radians(45)), math.tan(math.radians(4))
    z60 = 80.0 - 60.0 * t35
    z75 = z60 - 15.0 * t45
    if x <= 60.0:
        z = 80.0 - x * t35
    elif x <= 75.0:
        z = z60 - (x - 60.0) * t45
    else:
        z = z75 - (x - 75.0) * t4
    # the dam: up its 45-degree face, along the crest, down the far face (above the run-out)
    if 116.0 < x < 127.0:
        z += min(4.0, x - 116.0, 127.0 - x)
    return z


def main():
    out = sys.argv[1] if len(sys.argv) > 1 else os.path.join(ROOT, "data", "snow-slope-3d")
    os.makedirs(out, exist_ok=True)
    with open(os.path.join(out, "bed.asc"), "w") as f:
        f.write(f"ncols {NX}\nnrows {NY}\nxllcenter 0\nyllcenter 0\ncellsize {CELL:g}\nNODATA_value -9999\n")
        for r in range(NY - 1, -1, -1):  # north row first
            y = r * CELL
            f.write(" ".join(f"{profile(c * CELL) + 0.01 * (y - 20.0) ** 2:.4f}" for c in range(NX)) + "\n")
    print(f"wrote {out}/bed.asc: {NX} x {NY} nodes of {CELL:g} m, drop {profile(0) - profile(150):.1f} m")


if __name__ == "__main__":
    main()
