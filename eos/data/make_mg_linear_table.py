#!/usr/bin/python3
# SPDX-License-Identifier: MIT
"""Write a full (rho, e) EOS table in mscale's text format (docs/eos.md) sampled from the
Mie-Grueneisen linear Us-up form: P = P_H + G0 rho0 (e - e_H), eta = 1 - rho0/rho,
P_H = rho0 c0^2 eta / (1 - s eta)^2, e_H = P_H eta / (2 rho0)   (docs/design.md §3).

Usage: /usr/bin/python3 make_mg_linear_table.py OUT.txt [rho0 c0 s gamma0 rho_min rho_max n_rho
                                                         e_min e_max n_e]
Defaults: aluminium (2.703, 5.35, 1.34, 2.0) on rho 2.3..6.0 (75 values), e 0..20 (41 values).
With OUT ending in .h5 the same data are written as HDF5 (needs h5py).
The sound speed column is the exact c of the analytic EOS at each node.
"""
import sys

import numpy as np


def mg_linear(rho, e, rho0, c0, s, g0):
    eta = 1.0 - rho0 / rho
    den = 1.0 - s * eta
    ph = rho0 * c0 * c0 * eta / den**2
    eh = ph * eta / (2.0 * rho0)
    G = g0 * rho0
    p = ph + G * (e - eh)
    dph_deta = rho0 * c0 * c0 * (1.0 + s * eta) / den**3
    deta = rho0 / rho**2
    dph = dph_deta * deta
    deh = (dph_deta * eta + ph) / (2.0 * rho0) * deta
    c2 = dph - G * deh + p / rho**2 * G
    return p, np.sqrt(c2)


def main():
    out = sys.argv[1]
    a = [float(x) for x in sys.argv[2:]]
    rho0, c0, s, g0, rmin, rmax, nr, emin, emax, ne = (a + [2.703, 5.35, 1.34, 2.0, 2.3, 6.0, 75,
                                                            0.0, 20.0, 41][len(a):])
    rho = np.linspace(rmin, rmax, int(nr))
    e = np.linspace(emin, emax, int(ne))
    R, E = np.meshgrid(rho, e, indexing="ij")
    P, C = mg_linear(R, E, rho0, c0, s, g0)
    if out.endswith(".h5"):
        import h5py
        with h5py.File(out, "w") as f:
            for name, data, unit in (("rho", rho, "g/cm^3"), ("e", e, "kJ/g"), ("P", P, "GPa"),
                                     ("c", C, "km/s"), ("rho0", np.array([rho0]), "g/cm^3")):
                f[name] = data
                f[name].attrs["units"] = unit
        return
    with open(out, "w") as f:
        f.write("# Full EOS table sampled from the Mie-Grueneisen linear Us-up form\n")
        f.write(f"# (rho0 = {rho0}, c0 = {c0}, s = {s}, gamma0 = {g0}) by eos/data/"
                "make_mg_linear_table.py\n")
        f.write("# units: rho [g/cm^3], e [kJ/g], P [GPa], c [km/s]\n")
        f.write(f"# rho0: {rho0}\n")
        f.write("rho e P c\n")
        for i in range(len(rho)):
            for j in range(len(e)):
                f.write(f"{rho[i]:.10g} {e[j]:.10g} {P[i, j]:.10g} {C[i, j]:.10g}\n")


if __name__ == "__main__":
    main()
