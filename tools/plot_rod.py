#!/usr/bin/python3
# SPDX-License-Identifier: MIT
"""Plots for the Hamiltonian discrete model's paper-000 tests (docs/validation.md).

  plot_rod.py rod OUTDIR [OUTDIR2 ...] -o rod.png [--cross HISTORY.csv[:LABEL] ...]
      w(L/2, t) over the last 10 L/c: DM runs (dm_probes.csv of each OUTDIR, labelled by their
      particle count), the exact solution and optionally a cross-scheme history
      (continuum `history_quarter.csv`: columns t and x or w of the tagged node).
  plot_rod.py contact OUTDIR -o contact.png
      sigma_xx(x) of the last dm_profile_NNN.csv against its `exact` column.
  plot_rod.py sphere OUTDIR -o sphere.png
      radial displacement and velocity of every particle (dm_sphere_radial.csv) against r,
      with the exact solution.
  plot_rod.py slice OUTDIR -o slice.png
      "schlieren" pictures S = 0.8 exp(-5|u|/|u|max) of the first z layer ([Sofronov] Fig. 5)
      from every dm_profile_NNN.csv of a 3D run.

Run with Debian's python (/usr/bin/python3: numpy, matplotlib). Units g, cm, 10 us.
"""
import argparse
import glob
import math
import os
import sys

import numpy as np
import matplotlib

matplotlib.use("Agg")
import matplotlib.pyplot as plt  # noqa: E402

sys.path.insert(0, os.path.join(os.path.dirname(os.path.abspath(__file__)), "..", "python"))
import mscale  # noqa: E402  (python/mscale: the reader of mscale's outputs)


def column(table, k):
    """Column k (by position) of a Table, as floats."""
    return table[table.names[k]].astype(float)


def triangle_exact(x, t, L, eps, c):
    """d'Alembert form of [Sofronov] §5.1 (odd 4L-periodic extension of the triangle)."""
    def ext(y):
        y = np.mod(y + L, 4 * L) - L
        return np.where(y <= L, eps * y, eps * (2 * L - y))
    return 0.5 * (ext(x - c * t) + ext(x + c * t))


def rod(args):
    fig, ax = plt.subplots(figsize=(9, 5.2))
    L, c, eps = args.L, args.c, args.eps
    tmax = None
    for d in args.dirs:
        probes = mscale.read_csv(os.path.join(d, "dm_probes.csv"))
        t, w = column(probes, 0), column(probes, 1)
        xprobe = float(probes.names[1].split("(")[1].rstrip(")"))
        tmax = t[-1]
        sel = t >= tmax - 10 * L / c
        n = None
        summ = os.path.join(d, "dm_summary.csv")
        if os.path.exists(summ):
            n = int(mscale.read_csv(summ)["real_particles"][0])
        ax.plot(t[sel] * c / L, w[sel] * 1e4, lw=1.0,
                label=f"DM, {n} particles (x = {xprobe:g})" if n else f"DM {d}")
    tt = np.linspace(tmax - 10 * L / c, tmax, 4000)
    ax.plot(tt * c / L, triangle_exact(0.5 * L, tt, L, eps, c) * 1e4, "k--", lw=1.2,
            label="exact (x = L/2)")
    for spec in args.cross or []:
        path, _, label = spec.partition(":")
        hist = mscale.read_csv(path)
        t = column(hist, 0)
        name = "w" if "w" in hist else "x"
        w = hist[name].astype(float) - (0.5 * L if name == "x" else 0.0)
        sel = t >= tmax - 10 * L / c
        ax.plot(t[sel] * c / L, w[sel] * 1e4, lw=1.0, ls=":",
                label="cross scheme " + (label or path))
    ax.set_xlabel("t c / L")
    ax.set_ylabel("w(L/2, t)  [1e-4 cm]")
    ax.set_title("[Sofronov] §6.1: rod, triangle initial data, last 10 L/c before 250 L/c")
    ax.legend(loc="upper center", bbox_to_anchor=(0.5, -0.13), ncol=3, fontsize=8)
    ax.grid(alpha=0.3)
    fig.tight_layout()
    fig.savefig(args.o, dpi=110)


def contact(args):
    files = sorted(glob.glob(os.path.join(args.dirs[0], "dm_profile_*.csv")))
    prof = mscale.read_csv(files[-1])
    x, s, ex = column(prof, 0), prof["sigma_xx"], prof["exact"]
    fig, ax = plt.subplots(figsize=(9, 4.5))
    ax.plot(x, s, "-", lw=0.8, label="DM sigma_xx")
    ax.plot(x, ex, "k--", lw=1.0, label="exact")
    ax.axvline(1.0, color="gray", lw=0.8)
    ax.set_xlabel("x [cm]")
    ax.set_ylabel("sigma_xx [GPa]")
    ax.set_title("[Sofronov] §6.2: Fe | Be contact, t = 0.1 (10 us)")
    ax.legend(fontsize=8)
    ax.grid(alpha=0.3)
    fig.tight_layout()
    fig.savefig(args.o, dpi=110)


def sphere(args):
    radial = mscale.read_csv(os.path.join(args.dirs[0], "dm_sphere_radial.csv"))
    r, wr, ur, we, ue = (column(radial, i) for i in range(5))
    o = np.argsort(r)
    fig, ax = plt.subplots(1, 2, figsize=(11, 4.2))
    ax[0].plot(r, wr / args.w0, ".", ms=1, alpha=0.3, label="DM (all particles)")
    ax[0].plot(r[o], we[o] / args.w0, "k-", lw=1, label="exact")
    ax[0].set_xlabel("r [cm]")
    ax[0].set_ylabel("w_r / w0")
    u0 = args.w0 * 2 * math.pi / args.period
    ax[1].plot(r, ur / u0, ".", ms=1, alpha=0.3, label="DM (all particles)")
    ax[1].plot(r[o], ue[o] / u0, "k-", lw=1, label="exact")
    ax[1].set_xlabel("r [cm]")
    ax[1].set_ylabel("u_r / (w0 omega)")
    for a in ax:
        a.grid(alpha=0.3)
        a.legend(fontsize=8, markerscale=8)
    fig.suptitle("[Sofronov] §6.3: spherical wave from a cube source " + args.title)
    fig.tight_layout()
    fig.savefig(args.o, dpi=110)


def slice_(args):
    files = sorted(glob.glob(os.path.join(args.dirs[0], "dm_profile_*.csv")))
    fig, axs = plt.subplots(1, len(files), figsize=(3.6 * len(files), 4.3), squeeze=False)
    for ax, fn in zip(axs[0], files):
        prof = mscale.read_csv(fn)
        x, y = column(prof, 0), column(prof, 1)
        u = np.sqrt(sum(prof[k] ** 2 for k in ("u_x", "u_y", "u_z")))
        h = np.min(np.diff(np.unique(x)))
        nx, ny = int(round((x.max() - x.min()) / h)) + 1, int(round((y.max() - y.min()) / h)) + 1
        img = np.full((ny, nx), np.nan)
        out = np.maximum(np.abs(x), np.abs(y)) > args.r0  # outside the source cube
        umax = max(u[out].max(), 1e-300)
        img[np.rint((y[out] - y.min()) / h).astype(int), np.rint((x[out] - x.min()) / h).astype(int)] = \
            0.8 * np.exp(-5 * u[out] / umax)
        ax.imshow(img, origin="lower", cmap="gray", vmin=0, vmax=0.8,
                  extent=(x.min(), x.max(), y.min(), y.max()))
        ax.set_title(f"t = {prof.time:.3g}" if prof.time is not None else "")
        ax.set_xlabel("x [cm]")
    axs[0][0].set_ylabel("y [cm]")
    fig.suptitle("§6.3: |u| at z = h/2, S = 0.8 exp(-5|u|/|u|max) " + args.title, fontsize=9)
    fig.tight_layout()
    fig.savefig(args.o, dpi=110)


def main():
    ap = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    ap.add_argument("what", choices=["rod", "contact", "sphere", "slice"])
    ap.add_argument("dirs", nargs="+")
    ap.add_argument("-o", required=True, help="output PNG")
    ap.add_argument("--cross", action="append",
                    help="cross-scheme history CSV[:LABEL] (rod; repeatable)")
    ap.add_argument("--L", type=float, default=1.0)
    ap.add_argument("--c", type=float, default=math.sqrt(200 / 7.85))
    ap.add_argument("--eps", type=float, default=1e-3)
    ap.add_argument("--w0", type=float, default=0.01)
    ap.add_argument("--period", type=float, default=1.0)
    ap.add_argument("--r0", type=float, default=1.0, help="source cube half-size (slice)")
    ap.add_argument("--title", default="")
    args = ap.parse_args()
    {"rod": rod, "contact": contact, "sphere": sphere, "slice": slice_}[args.what](args)
    return 0


if __name__ == "__main__":
    sys.exit(main())
