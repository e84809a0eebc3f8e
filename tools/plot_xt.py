#!/usr/bin/python3
# SPDX-License-Identifier: MIT
"""x–t diagram of a continuum run (density or pressure on the moving Lagrangian grid).

Usage:  /usr/bin/python3 tools/plot_xt.py OUTDIR [--quantity density|pressure] [--log]
                                          [--tags] [-o FILE.png]

Reads OUTDIR/xt.h5 (written by `mscale run` for `problem: continuum`, see
docs/input-continuum.md): t [nf], x [nf][ncol+1] node positions, rho and p [nf][ncol].
Each frame's cells are drawn as quadrilaterals between consecutive frames, so the picture
follows the material (contacts are sharp lines). With --tags the tagged nodes' histories
(history.h5) are overlaid. Writes OUTDIR/xt_<quantity>.png unless -o is given.
Needs Debian's numpy, h5py and matplotlib (run with /usr/bin/python3).
"""
import argparse
import os
import sys

import matplotlib
matplotlib.use("Agg")
import matplotlib.pyplot as plt  # noqa: E402
import numpy as np  # noqa: E402
from matplotlib.colors import LogNorm, TwoSlopeNorm  # noqa: E402

sys.path.insert(0, os.path.join(os.path.dirname(os.path.abspath(__file__)), "..", "python"))
import mscale  # noqa: E402  (python/mscale: the reader of mscale's outputs)


def time_scale(unit):
    """(factor to us, axis unit) for a time unit; the unit itself when it is not a time."""
    try:
        return mscale.us_per(unit), "us"
    except ValueError:
        return 1.0, unit


def plot_xt(outdir, quantity=None, log=False, tags=False, output=None):
    """Draw the x–t diagram of OUTDIR/xt.h5; returns the PNG path."""
    a = argparse.Namespace(outdir=outdir, quantity=quantity, log=log, tags=tags, output=output)
    path = os.path.join(a.outdir, "xt.h5")
    if not os.path.exists(path):
        sys.exit(f"plot_xt: {path} not found (set output.xt_frames > 0 in the deck)")
    xt = mscale.read_h5_group(path)
    t = xt["t"].ravel()
    x = xt["x"]
    q_attr = str(xt.attrs.get("quantity", "rho"))
    quantity = a.quantity or ("pressure" if q_attr == "p" else "density")
    data = xt["p" if quantity == "pressure" else "rho"]
    tunit = xt.units.get("t", "10us")
    if len(t) < 2:
        sys.exit("plot_xt: fewer than two frames in xt.h5")
    # Quadrilateral mesh in (x, t): frame k's nodes against times between frames.
    tb = np.empty(len(t) + 1)
    tb[1:-1] = 0.5 * (t[1:] + t[:-1])
    tb[0], tb[-1] = t[0], t[-1]
    xb = np.empty((len(t) + 1, x.shape[1]))
    xb[1:-1] = 0.5 * (x[1:] + x[:-1])
    xb[0], xb[-1] = x[0], x[-1]
    T = np.repeat(tb[:, None], x.shape[1], axis=1)

    # times in microseconds (the internal unit is 10 us)
    tscale, tlabel = time_scale(tunit)
    T = T * tscale
    fig, ax = plt.subplots(figsize=(8, 6))
    norm, cmap = None, "viridis"
    if a.log:
        pos = data[data > 0]
        norm = LogNorm(vmin=pos.min(), vmax=pos.max()) if pos.size else None
    elif quantity == "pressure" and data.min() < 0 < data.max():
        # signed pressure: a diverging map centred on zero, tension blue, compression red
        norm, cmap = TwoSlopeNorm(vmin=data.min(), vcenter=0.0, vmax=data.max()), "RdBu_r"
    mesh = ax.pcolormesh(xb, T, data, shading="flat", cmap=cmap, norm=norm)
    # only the disturbed part of the grid: cells whose state ever left the initial one (the
    # undisturbed gas ahead of the free surface is most of the picture otherwise)
    moved = np.abs(data - data[0]).max(axis=0) > 1e-9 * max(np.abs(data).max(), 1e-300)
    if moved.any():
        cols = np.flatnonzero(moved)
        x_lo, x_hi = x[:, cols[0]].min(), x[:, cols[-1] + 1].max()
        pad = 0.05 * (x_hi - x_lo)
        ax.set_xlim(max(x.min(), x_lo - pad), min(x.max(), x_hi + pad))
    label = "density [g/cm^3]" if quantity == "density" else "pressure [GPa]"
    fig.colorbar(mesh, ax=ax, label=label)
    if a.tags:
        hist = mscale.Run(a.outdir).histories_from_h5()  # full precision
        if hist:
            for name, h in hist.items():
                ax.plot(h["x"].ravel(), tscale * h["t"].ravel(),
                        lw=1.2, color="k", ls="--" if "free" in name else "-", label=name)
            ax.legend(loc="upper left", fontsize=8)
    ax.set_xlabel("x [cm]")
    ax.set_ylabel(f"t [{tlabel}]")
    ax.set_title(f"x–t diagram: {quantity}")
    out = a.output or os.path.join(a.outdir, f"xt_{quantity}.png")
    fig.tight_layout()
    fig.savefig(out, dpi=120)
    plt.close(fig)
    return out


def plot_histories(outdir, output):
    """Velocity and position histories of the tagged nodes (the U(t) that drives particles)."""
    hist = mscale.Run(outdir).histories_from_h5()  # full precision
    names = [n for n, h in hist.items() if "t" in h and "u" in h]
    if not names:
        return None
    fig, (ax1, ax2) = plt.subplots(1, 2, figsize=(10, 4))
    for name in names:
        h = hist[name]
        t = mscale.to_us(h["t"].ravel(), h.unit("t"))  # us
        ax1.plot(t, h["u"].ravel(), label=name)
        ax2.plot(t, h["x"].ravel(), label=name)
    ax1.set_xlabel("t [us]"); ax1.set_ylabel("u [km/s]"); ax1.set_title("Tagged nodes: U(t)")
    ax2.set_xlabel("t [us]"); ax2.set_ylabel("x [cm]"); ax2.set_title("Tagged nodes: x(t)")
    ax1.legend(fontsize=8); ax2.legend(fontsize=8)
    fig.tight_layout()
    fig.savefig(output, dpi=120)
    plt.close(fig)
    return output


def plot_run(outdir, plotdir):
    """Hook for tools/plot_run.py: every continuum picture of a run directory."""
    made = []
    if os.path.exists(os.path.join(outdir, "xt.h5")):
        for q in ("density", "pressure"):
            made.append(plot_xt(outdir, q, log=False, tags=True,
                                output=os.path.join(plotdir, f"xt_{q}.png")))
    if os.path.exists(os.path.join(outdir, "history.h5")):
        out = plot_histories(outdir, os.path.join(plotdir, "histories.png"))
        if out:
            made.append(out)
    return made


def main():
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("outdir")
    ap.add_argument("--quantity", choices=["density", "pressure"], default=None,
                    help="default: the deck's output.xt_quantity")
    ap.add_argument("--log", action="store_true", help="logarithmic colour scale")
    ap.add_argument("--tags", action="store_true", help="overlay tagged-node trajectories")
    ap.add_argument("-o", "--output", default=None)
    a = ap.parse_args()
    print(plot_xt(a.outdir, a.quantity, a.log, a.tags, a.output))


if __name__ == "__main__":
    main()
