# SPDX-License-Identifier: MIT
"""Compare two coupled-problem run directories made on different rank counts (tests/mpi/cpl_cli.sh,
tests/mpi/cpl_two_way.sh; docs/mpi.md "The coupled problem on MPI ranks"):
- spectra (spectrum.csv, spectrum_detector.csv, every spectrum_NNNN.csv): counts exact, masses
  to 1e-12 relative (the same equal masses summed in another order);
- fragments.csv: sizes exact; the other columns to 1e-8 of their scale, except the centre along
  the periodic axes and R_g of the bulk, which spans the whole periodic width, where the circular
  mean is round-off (docs/mpi.md "Fragments on MPI ranks");
- each CSV named with --csv: every column to --tol (default 1e-8) of its scale (NaN where the
  reference has NaN);
- arrivals.csv: to 1e-4 of the column scale (the callers say why);
- the last particle snapshot by gid: every particle once, the same fragment ids, positions within
  --dx cm, velocities within --dv km/s, kinetic energy within --dv relative.
usage: compare_cpl_runs.py REF RUN --dx TOL --dv TOL [--tol TOL] [--csv FILE ...]"""
import argparse
import glob
import os

import h5py
import numpy as np

ap = argparse.ArgumentParser()
ap.add_argument("ref")
ap.add_argument("run")
ap.add_argument("--dx", type=float, required=True)
ap.add_argument("--dv", type=float, required=True)
ap.add_argument("--tol", type=float, default=1e-8)
ap.add_argument("--csv", nargs="*", default=[])
args = ap.parse_args()
a, b = args.ref, args.run


def table(d, f):
    lines = [l for l in open(os.path.join(d, f)) if not l.startswith("#")]
    return np.atleast_1d(np.genfromtxt(lines, delimiter=",", names=True))


spectra = ["spectrum.csv", "spectrum_detector.csv"] + sorted(
    os.path.basename(p) for p in glob.glob(os.path.join(a, "spectrum_0*.csv")))
for f in spectra:
    x, y = table(a, f), table(b, f)
    assert x.shape == y.shape and (x["g"] == y["g"]).all() and (x["count"] == y["count"]).all(), f
    assert np.allclose(x["mass"], y["mass"], rtol=1e-12, atol=0), f
nfrag = int(table(a, "spectrum.csv")["count"].sum())
print(f"{b}: {len(spectra)} spectra identical ({nfrag} fragments)")


def close(f, skip=lambda name, x: np.zeros(len(x), bool), tol=1e-8):
    x, y = table(a, f), table(b, f)
    assert x.shape == y.shape, (f, x.shape, y.shape)
    worst = 0.0
    for name in x.dtype.names:
        keep = ~skip(name, x) & ~np.isnan(x[name])
        assert (np.isnan(y[name]) == np.isnan(x[name])).all(), (f, name, "NaN pattern")
        scale = max(np.abs(x[name][keep]).max(initial=0), 1e-300)
        err = np.abs(x[name] - y[name])[keep].max(initial=0) / scale
        worst = max(worst, err)
        assert err < tol, (f, name, err)
    print(f"{b}: {f} max deviation {worst:.2e} of the column scale")


fr = table(a, "fragments.csv")
assert (fr["count"] == table(b, "fragments.csv")["count"]).all(), "fragment sizes"
bulk = fr["count"] == fr["count"].max()
close("fragments.csv", lambda name, x: bulk if name in ("y", "z", "rg") else np.zeros(len(x), bool))
for f in args.csv:
    close(f, tol=args.tol)
close("arrivals.csv", tol=1e-4)
last = sorted(glob.glob(os.path.join(a, "particles_*.h5")))[-1]
with h5py.File(last) as r, h5py.File(os.path.join(b, os.path.basename(last))) as h:
    g, gr = h["particles/gid"][:], r["particles/gid"][:]
    assert len(g) == len(gr) and len(np.unique(g)) == len(g), "every particle once"
    o, orf = np.argsort(g), np.argsort(gr)
    assert (g[o] == gr[orf]).all()
    dx = np.abs(h["particles/x"][:][o] - r["particles/x"][:][orf]).max()
    dv = np.abs(h["particles/v"][:][o] - r["particles/v"][:][orf]).max()
    assert (h["particles/fragment"][:][o] == r["particles/fragment"][:][orf]).all(), "fragment ids"

    def ke(f, k):
        return 0.5 * (f["particles/mass"][:][k] * (f["particles/v"][:][k] ** 2).sum(1)).sum()

    de = abs(ke(h, o) - ke(r, orf)) / ke(r, orf)
    print(f"{b}: {len(g)} particles: max |dx| {dx:.1e} cm, |dv| {dv:.1e} km/s, "
          f"kinetic energy {de:.1e}")
    assert dx < args.dx and dv < args.dv and de < args.dv, (dx, dv, de)
