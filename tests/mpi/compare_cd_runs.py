# SPDX-License-Identifier: MIT
"""Compare two cluster_dynamics run directories made on different rank counts (tests/mpi/*.sh):
the CSV files must agree to relative 1e-8 of each column's scale (the runs differ by force
summation order only: ~1e-13 after the tests' steps), and the last snapshot must hold every
particle exactly once with positions within 1e-12 cm of the reference.
usage: compare_cd_runs.py REF_DIR RUN_DIR"""
import glob
import os
import sys

import h5py
import numpy as np

ref, run = sys.argv[1], sys.argv[2]
for f in ("cd_energy.csv", "cd_profiles.csv", "cd_front.csv"):
    x = np.genfromtxt(os.path.join(ref, f), delimiter=",", comments="#")
    y = np.genfromtxt(os.path.join(run, f), delimiter=",", comments="#")
    x, y = x[np.isfinite(x).all(axis=1)], y[np.isfinite(y).all(axis=1)]
    assert x.shape == y.shape, (f, x.shape, y.shape)
    err = (np.abs(x - y) / np.maximum(np.abs(x).max(axis=0), 1e-300)).max()
    print(f"{os.path.basename(run)}: {f} max deviation {err:.2e} of the column scale")
    assert err < 1e-8, (f, err)
snaps = sorted(glob.glob(os.path.join(run, "particles_[0-9]*.h5")))
refs = sorted(glob.glob(os.path.join(ref, "particles_[0-9]*.h5")))
assert snaps and refs and os.path.basename(snaps[-1]) == os.path.basename(refs[-1]), (snaps, refs)
with h5py.File(snaps[-1]) as h, h5py.File(refs[-1]) as r:
    g, gr = h["particles/gid"][:], r["particles/gid"][:]
    assert len(g) == len(gr) and len(np.unique(g)) == len(g), "gids"
    o, orr = np.argsort(g), np.argsort(gr)
    assert (g[o] == gr[orr]).all()
    dx = np.abs(h["particles/x"][:][o] - r["particles/x"][:][orr]).max()
    print(f"{os.path.basename(run)}: snapshot of {len(g)} particles, max |dx| {dx:.2e} cm")
    assert dx < 1e-12, dx
