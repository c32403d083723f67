#!/usr/bin/env python3
"""The Attabad-like valley of scenarios/attabad-3d.toml (issue 47), as ESRI ASCII grids.

usage: scripts/attabad-valley.py [OUT_DIR]    (default data/attabad-3d)

Writes bed.asc (the terrain after failure: the rupture surface in the scar, the slope that
stayed elsewhere, the valley floor and the opposite side) and top.asc (the slope before the
failure: the release's top surface). Reproducible: no random numbers.

Published (docs/debris.md, DEBRIS.md sec. 1 and its sources): the cross-section of
data/attabad-2d-section.csv (scar height 1175 m, the mass 1060 m from the crown to the valley
floor, the 200 m floor, the opposite rock cliff), the 45 Mm3 volume. Constructed: that the
section holds all along the scar, the valley straight and level along y (the river's course
taken as the y axis), the scar 1,291 m wide (45 Mm3 over the section's 34,850 m2) with flanks
that taper the failed depth to zero over 100 m either side, and the grid's 20 m cells.
"""
import math
import os
import sys

ROOT = os.path.dirname(os.path.dirname(os.path.abspath(__file__)))
CELL = 20.0
X0, X1 = -400.0, 1900.0      # across the valley: the section's x, from the north ridge southwards
Y0, Y1 = -2400.0, 2400.0     # along the valley: the river's course
SCAR = 45e6 / 34850.0        # m, the scar's width: the volume over the section's area
FLANK = 100.0                # m, over which the failed depth tapers to 0 at each side


def section():
    pts = []
    with open(os.path.join(ROOT, "data", "attabad-2d-section.csv")) as f:
        for line in f:
            if line.startswith("#") or line.startswith("x_m"):
                continue
            x, y = line.split(",")
            pts.append((float(x), float(y)))
    return pts


def interpolate(pts, x):
    if x <= pts[0][0]:
        return pts[0][1]
    for (xa, ya), (xb, yb) in zip(pts, pts[1:]):
        if x <= xb:
            return ya + (yb - ya) * (x - xa) / (xb - xa)
    return pts[-1][1]


def main():
    out = sys.argv[1] if len(sys.argv) > 1 else os.path.join(ROOT, "data", "attabad-3d")
    os.makedirs(out, exist_ok=True)
    bed_line = section()
    # the slope before the failure: the straight line C-M over the scar (x 0..700), the
    # section elsewhere
    c, m = bed_line[1], (700.0, 399.0)

    def before(x):
        if c[0] <= x <= m[0]:
            return c[1] + (m[1] - c[1]) * (x - c[0]) / (m[0] - c[0])
        return interpolate(bed_line, x)

    def lateral(y):
        """1 inside the scar, a cosine taper over the flanks, 0 outside; its integral is SCAR"""
        a = abs(y) - (SCAR / 2 - FLANK / 2)
        if a <= 0:
            return 1.0
        if a >= FLANK:
            return 0.0
        return 0.5 * (1 + math.cos(math.pi * a / FLANK))

    ncols = int(round((X1 - X0) / CELL)) + 1
    nrows = int(round((Y1 - Y0) / CELL)) + 1
    bed, top = [], []
    volume = 0.0
    for r in range(nrows):
        y = Y0 + r * CELL
        rb, rt = [], []
        for col in range(ncols):
            x = X0 + col * CELL
            z_before = before(x)
            depth = max(0.0, z_before - interpolate(bed_line, x)) * lateral(y)
            rb.append(z_before - depth)
            rt.append(z_before)
            volume += depth * CELL * CELL
        bed.append(rb)
        top.append(rt)
    for name, grid in (("bed.asc", bed), ("top.asc", top)):
        with open(os.path.join(out, name), "w") as f:
            f.write(f"ncols {ncols}\nnrows {nrows}\nxllcenter {X0:g}\nyllcenter {Y0:g}\ncellsize {CELL:g}\nNODATA_value -9999\n")
            for row in reversed(grid):  # the northernmost row first (largest y)
                f.write(" ".join(f"{z:.2f}" for z in row) + "\n")
    print(f"{out}: {ncols} x {nrows} cells of {CELL:g} m; the failed mass {volume / 1e6:.1f} Mm3 (scar {SCAR:.0f} m wide)")


if __name__ == "__main__":
    main()
