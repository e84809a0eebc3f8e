#!/usr/bin/python3
# SPDX-License-Identifier: MIT
"""Why the hole of a sphere-on-plate `impact` run grows: the plate remnant's lip between two
particle snapshots (docs/validation.md, "Piekutowski perforation"; the remnant and its hole are
those of tools/piekutowski.py).

  piekutowski_lip.py OUTDIR K0 K1

K0 < K1 are indices into the run's particle snapshots. Printed, at K1 unless said otherwise:

* the lip (the remnant's particles within 2h of its hole): number, failed share, mass-mean and
  largest radial velocity u_r;
* the intact lip particles' J = det F with F by least squares over their whole family (the
  lattice sites within the horizon δ: what the stress pass uses, so J here is ρ0/ρ), and over
  the family's intact members only (median and 10 / 90 %);
* from K0 to K1: the plate particles that failed (number, where they are and were, speed) and
  the particles the remnant lost (number, share already failed at K0);
* the intact plate particles at K0 dilated to ρ/ρ0 ≤ 0.99 (a mean tension of ≳ 0.7 GPa in Al):
  the share of them failed, still so dilated, and relaxed at K1.

Units: mm, km/s in the printout. Debian's python (/usr/bin/python3: numpy, scipy).
"""
import os
import sys

import numpy as np
from scipy.spatial import cKDTree

sys.path.insert(0, os.path.dirname(os.path.abspath(__file__)))
import piekutowski  # noqa: E402  (the remnant, its hole, the bonds)

DILATED = 0.99  # ρ/ρ0 of the "dilated" intact particles


def state(run, g, k):
    s = run.snapshots[k]
    st = {c: np.asarray(s[c], float) for c in ("x", "X0", "v", "density")}
    st["body"] = np.asarray(s["body"]).astype(int)
    st["failed"] = np.asarray(s["failed"]) > 0
    lab = piekutowski.fragments(st["X0"], st["body"], st["failed"], g["h"], g["delta"],
                                x=st["x"], tear=piekutowski.TEAR)
    st["rem"] = piekutowski.plate_remnant(lab, st["X0"], st["body"], g)[0]
    d = st["x"][:, :2] - g["axis"]
    st["r"] = np.hypot(d[:, 0], d[:, 1])
    st["ur"] = np.sum(d * st["v"][:, :2], axis=1) / np.maximum(st["r"], 1e-300)
    st["hole"] = piekutowski.hole_outline(d[st["rem"], 0], d[st["rem"], 1])[0]
    st["t"] = s.time * (1.0 if s.time_unit == "us" else 10.0)  # µs
    return st


def family_J(st, g, i, members):
    """det of the least-squares F of particle i over the given family members."""
    xi = st["X0"][members] - st["X0"][i]
    y = st["x"][members] - st["x"][i]
    A = xi.T @ xi
    if len(members) < 4 or np.linalg.matrix_rank(A) < 3:
        return np.nan
    return np.linalg.det((y.T @ xi) @ np.linalg.inv(A))


def pct(a, q=(10, 50, 90), f="{:.4g}"):
    """Percentiles of the finite values of a ("-": none, e.g. no lip particle with four intact
    members spanning 3D)."""
    a = np.asarray(a, float)
    a = a[np.isfinite(a)]
    return " / ".join(f.format(v) for v in np.percentile(a, q)) + f" (of {len(a)})" if len(a) \
        else "-"


def main(argv):
    if len(argv) != 3:
        raise SystemExit(__doc__)
    run = piekutowski.mscale.Run(argv[0])
    g = piekutowski.geometry(run)
    rho0 = {0: None, 1: None}
    mats = {m["name"]: m for m in run.deck["materials"]}
    for bd in (0, 1):
        mat = mats[run.deck["impact"]["bodies"][bd]["material"]]
        rho0[bd] = float(mat["eos"]["rho0"])
    A, B = state(run, g, int(argv[1])), state(run, g, int(argv[2]))
    plate = B["body"] == 1
    lip = B["rem"] & (B["r"] < 0.5 * B["hole"] + 2 * g["h"])
    print(f"{argv[0]}: t {A['t']:.3f} -> {B['t']:.3f} us, h {10 * g['h']:.4g} mm, remnant's hole "
          f"{10 * A['hole']:.3f} -> {10 * B['hole']:.3f} mm")
    print(f"  lip at {B['t']:.2f} us: {lip.sum()} particles, failed {B['failed'][lip].mean():.2f}, "
          f"u_r mean {B['ur'][lip].mean():.3f} max {B['ur'][lip].max():.3f} km/s")
    idx = np.nonzero(plate)[0]
    tree = cKDTree(B["X0"][idx])
    Jall, Jint = [], []
    for i in np.nonzero(lip & ~B["failed"])[0]:
        fam = idx[tree.query_ball_point(B["X0"][i], g["delta"] * (1 - 1e-9))]
        fam = fam[fam != i]
        Jall.append(family_J(B, g, i, fam))
        Jint.append(family_J(B, g, i, fam[~B["failed"][fam]]))
    print(f"  intact lip particles: J over the whole family {pct(Jall)}, over its intact "
          f"members {pct(Jint)} (10 / 50 / 90 %)")
    new = plate & B["failed"] & ~A["failed"]
    lost = A["rem"] & ~B["rem"]
    r0 = np.hypot(*(B["X0"][:, :2] - g["axis"]).T)
    sp = np.linalg.norm(B["v"], axis=1)
    print(f"  failed from {A['t']:.2f} to {B['t']:.2f} us: {new.sum()} plate particles, r now "
          f"{pct(10 * B['r'][new])} mm, initially {pct(10 * r0[new])} mm, speed "
          f"{pct(sp[new])} km/s; lost from the remnant {lost.sum()}, "
          f"{A['failed'][lost].mean() if lost.any() else 0:.2f} of them failed before")
    dil = plate & ~A["failed"] & (A["density"] / rho0[1] <= DILATED)
    still = ~B["failed"] & (B["density"] / rho0[1] <= DILATED)
    print(f"  intact plate particles at rho/rho0 <= {DILATED} at {A['t']:.2f} us: {dil.sum()}; at "
          f"{B['t']:.2f} us failed {B['failed'][dil].mean():.2f}, intact and still so "
          f"{still[dil].mean():.2f}, relaxed {(~B['failed'] & ~still)[dil].mean():.2f}; "
          f"rho/rho0 at {A['t']:.2f} us of those failing by {B['t']:.2f} us "
          f"{pct(A['density'][new & ~A['failed']] / rho0[1])}")
    return 0


if __name__ == "__main__":
    sys.exit(main(sys.argv[1:]))
