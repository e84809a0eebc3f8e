# SPDX-License-Identifier: MIT
"""The hole in the recovered plate of tools/piekutowski.py against plates with a known hole
(docs/validation.md, "Piekutowski perforation"; no run: lattices built here).

    /usr/bin/python3 tests/python/test_piekutowski_hole.py SOURCE_DIR

A square-lattice plate (spacing h, three layers, 40 mm square) with the sites inside radius R
removed has a hole of diameter 2R: the equal-area diameter from the innermost site of each
sector, must be 2R to within h/2 (the sites nearest the hole lie between R and R + h in each
10° sector, several spacings wide, so the innermost is close to R: the lattice's cells cover
r ≥ R in the mean; measured 2R + 0.15 h; the wall taken h/2 inside the particle would read
2R − 0.85 h and fail). Then the same plate with what
the remnant must leave out: failed grains inside the hole (bonds between failed particles are
broken; those next to the lip moved away from it, their bonds to it torn), and an intact
particle of the lip thrown inwards (its bonds stretched beyond twice their
length: torn): the hole must not change.
"""
import os
import sys

import numpy as np

sys.path.insert(0, os.path.join(sys.argv[1], "python"))
sys.path.insert(0, os.path.join(sys.argv[1], "tools"))
import piekutowski  # noqa: E402

h, R = 0.03, 0.87  # cm: a t/7-like spacing, the 17.4 mm hole of the experiment's size
n = int(round(2.0 / h))
ii, jj, kk = np.meshgrid(np.arange(-n, n + 1), np.arange(-n, n + 1), np.arange(3), indexing="ij")
X0 = np.stack([ii.ravel() * h, jj.ravel() * h, kk.ravel() * h], axis=1)
g = dict(h=h, delta=1.5 * h, axis=np.zeros(2), half=np.array([n * h, n * h]))
checks = []


def hole(X0, x, failed):
    body = np.ones(len(X0), int)
    lab = piekutowski.fragments(X0, body, failed, h, g["delta"], x=x, tear=piekutowski.TEAR)
    rem, rim_frac = piekutowski.plate_remnant(lab, X0, body, g)
    d = piekutowski.hole_outline(x[rem, 0], x[rem, 1])
    return d, rim_frac


# the holed plate, every particle intact and at its site
r0 = np.hypot(X0[:, 0], X0[:, 1])
keep = r0 >= R
P = X0[keep]
(D, Dmin, Dmax), rim = hole(P, P.copy(), np.zeros(len(P), bool))
checks.append((abs(D - 2 * R) < 0.5 * h and rim == 1.0,
               f"punched plate: hole {10 * D:.3f} mm (sectors {10 * Dmin:.3f}-{10 * Dmax:.3f}) "
               f"against {20 * R:.3f} mm, within h/2 = {5 * h:.2f} mm"))

# what the experiment's plate does not hold: failed grains filling the hole where they broke
# off (the sites inside R, all failed: their mutual bonds broken; their bonds to the lip's
# intact sites stay, so they are moved 0.5 h inwards per unit of r: they are debris flying
# in, each bond to the lip stretched beyond 2), one intact lip particle thrown to the axis,
x = X0.copy()
failed = r0 < R
inner = failed & (r0 > 0)
x[inner, :2] *= (0.3 * r0[inner] / R)[:, None]  # the grains packed towards the axis
lip = np.nonzero(keep & (r0 < R + h))[0][0]
x[lip, :2] = [0.1 * R, 0.0]  # torn from the lip and thrown inwards
(D2, _, _), rim2 = hole(X0, x, failed)
# the thrown particle is gone from its sector, so the hole grows there by up to one site's
# spacing in one of 36 sectors: the equal-area diameter by ≤ h/36-ish; h/4 allows it
checks.append((abs(D2 - D) < 0.25 * h and rim2 == 1.0,
               f"with failed grains and a torn particle inside: hole {10 * D2:.3f} mm against "
               f"{10 * D:.3f} mm"))
if os.environ.get("PIEK_PRINT"):
    for _, what in checks:
        print(what)
bad = [what for ok, what in checks if not ok]
if bad:
    sys.exit("test_piekutowski_hole: FAILED: " + "; ".join(bad))
print("test_piekutowski_hole: all checks passed")
