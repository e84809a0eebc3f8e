#!/usr/bin/python3
# SPDX-License-Identifier: MIT
"""Writes the HDF5 files of the bad-input corpus (tests/reliability/bad/data/*.h5).
Run with Debian's python: /usr/bin/python3 make_bad_h5.py  (needs h5py, numpy).
Full EOS tables (docs/eos.md: datasets rho [nr], e [ne], P [nr][ne], c [nr][ne], rho0 [1])
and particle snapshots for `mscale spectrum` (docs/coupling.md: /particles/x [n][3],
/particles/mass [n], attribute r0 of /particles), each damaged in one way."""
import h5py
import numpy as np

rho = np.linspace(2.3, 6.0, 6)
e = np.linspace(0.0, 20.0, 5)
P = 5.35**2 * (rho[:, None] - 2.703) + 2.0 * 2.703 * e[None, :]
c = np.sqrt(5.35**2 + 0.1 * e[None, :] + 0 * rho[:, None])


def table(name, drop=(), P_group=False, P_shape=None):
    with h5py.File(name, "w") as f:
        f["rho"] = rho
        f["e"] = e
        if P_group:
            f.create_group("P")
        elif P_shape is not None:
            f["P"] = np.ones(P_shape)
        else:
            f["P"] = P
        f["c"] = c
        if "rho0" not in drop:
            f["rho0"] = np.array([2.703])


table("full_P_group.h5", P_group=True)
table("full_P_shape.h5", P_shape=(5, 6))
table("full_no_rho0.h5", drop=("rho0",))
table("full_ok_for_truncation.h5")
data = open("full_ok_for_truncation.h5", "rb").read()
open("full_truncated.h5", "wb").write(data[: len(data) // 2])

n = 8
x = np.stack([np.arange(n) * 1e-3, np.zeros(n), np.zeros(n)], axis=1)
mass = np.full(n, 1e-9)


def snapshot(name, x=x, mass=mass, r0=1e-3, x_name="x", gid=None):
    with h5py.File(name, "w") as f:
        g = f.create_group("particles")
        if gid is not None:
            g["gid"] = gid
        if r0 is not None:
            g.attrs["r0"] = r0
        if x is not None:
            g[x_name] = x
        if mass is not None:
            g["mass"] = mass


snapshot("snap_no_x.h5", x=None)
snapshot("snap_x_4cols.h5", x=np.concatenate([x, x[:, :1]], axis=1))
snapshot("snap_mass_length.h5", mass=mass[:5])
xnan = x.copy()
xnan[3, 1] = np.nan
snapshot("snap_x_nan.h5", x=xnan)
snapshot("snap_no_r0.h5", r0=None)
snapshot("snap_x_int.h5", x=np.zeros((n, 3), dtype=np.int32))
snapshot("snap_gid_repeated.h5", gid=np.array([0, 1, 2, 3, 3, 5, 6, 7], dtype=np.int64))
import os
os.remove("full_ok_for_truncation.h5")
