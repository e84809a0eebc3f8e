#!/usr/bin/python3
# SPDX-License-Identifier: MIT
"""Plots of a `coupled` run (docs/coupling.md): the drive and the particle snapshots.

Usage: /usr/bin/python3 tools/plot_coupled.py RUNDIR        # PNGs into RUNDIR/plots/

  drive.png              U(t) of the drive node (history_<tag>.csv of the grid) and the
                         free-surface velocity of the grid vs the particles (free_surface.csv)
  interface.png          two-way runs: interface and free-surface velocities, interface
                         impulse and work as the grid gave and the particles received them
  particles_NNNN.png     particle snapshots (particles_NNNN.h5): the free-surface region
                         coloured by velocity, and the ejecta's fragments in (x, vx)
Also offers plot_run(outdir, plotdir) for tools/plot_run.py. Debian's numpy/h5py/matplotlib.
"""
import glob
import os
import sys

import matplotlib

matplotlib.use("Agg")
import matplotlib.pyplot as plt  # noqa: E402
import numpy as np  # noqa: E402

HERE = os.path.dirname(os.path.abspath(__file__))
sys.path.insert(0, HERE)
sys.path.insert(0, os.path.join(HERE, "..", "python"))
import mscale  # noqa: E402  (python/mscale: the reader of mscale's outputs)
from plot_spectrum import lab, read_csv  # noqa: E402


def plot_drive(outdir, plotdir):
    fs = os.path.join(outdir, "free_surface.csv")
    if not os.path.exists(fs):
        return []
    fig, ax = plt.subplots(figsize=(7.5, 4.5))
    # the grid's tag histories (the drive node is the one named in the deck; show them all)
    for h in sorted(glob.glob(os.path.join(outdir, "history_*.csv"))):
        c, u, _ = read_csv(h)
        name = os.path.basename(h)[len("history_"):-4]
        ax.plot(c["t"], c["u"], lw=1, label=f"grid node '{name}'")
    c, u, _ = read_csv(fs)
    ax.plot(c["t"], c["u_particles"], "k.", ms=2, label="particles: free-surface layer")
    ax.set_xlabel(lab("t", u))
    ax.set_ylabel(lab("u_grid", u).replace("u_grid", "velocity"))
    ax.set_title("drive U(t) and free-surface velocity: grid vs particles")
    ax.grid(True, alpha=0.3)
    ax.legend(fontsize=8)
    if len(c["t"]):
        ax.set_xlim(min(c["t"]) - 0.02, max(c["t"]))
    fig.tight_layout()
    out = os.path.join(plotdir, "drive.png")
    fig.savefig(out, dpi=120)
    plt.close(fig)
    return [out]


def plot_interface(outdir, plotdir):
    """Two-way runs: interface velocity, particle free surface, the interface balance."""
    path = os.path.join(outdir, "interface.csv")
    if not os.path.exists(path):
        return []
    c, u, _ = read_csv(path)
    fig, (a1, a2) = plt.subplots(1, 2, figsize=(12, 4.5))
    a1.plot(c["t"], c["u_interface"], label="interface node (grid)")
    a1.plot(c["t"], c["u_free_surface"], label="free surface (particles)")
    a1.set_xlabel(lab("t", u))
    a1.set_ylabel("velocity [km/s]")
    a1.set_title("two-way coupling: velocities")
    a1.grid(True, alpha=0.3)
    a1.legend(fontsize=8)
    a2.plot(c["t"], -c["J_grid"], label="impulse given by the grid (-J_grid)")
    a2.plot(c["t"], c["J_particles"], "--", label="impulse received by the particles")
    a2.plot(c["t"], -c["W_grid"], label="work given by the grid (-W_grid)")
    a2.plot(c["t"], c["W_particles"], "--", label="work received by the particles")
    a2.set_xlabel(lab("t", u))
    a2.set_ylabel(f"impulse [{u.get('J_grid', '?')}], work [{u.get('W_grid', '?')}]")
    a2.set_title("interface balance")
    a2.grid(True, alpha=0.3)
    a2.legend(fontsize=8)
    fig.tight_layout()
    out = os.path.join(plotdir, "interface.png")
    fig.savefig(out, dpi=120)
    plt.close(fig)
    return [out]


def time_label(t, unit="10us"):
    """A time in microseconds for titles (the internal unit is 10 us)."""
    try:
        return f"t = {mscale.to_us(t, unit):.3g} us"
    except ValueError:
        return f"t = {t:.4g} {unit}"


def fragment_table(x, v, mass, frag):
    """Per fragment (ids >= 0): mass, centre of mass, c.o.m. velocity along x; sorted by id."""
    ids, inv = np.unique(frag[frag >= 0], return_inverse=True)
    sel = frag >= 0
    m = np.bincount(inv, weights=mass[sel])
    cx = np.bincount(inv, weights=mass[sel] * x[sel, 0]) / m
    cy = np.bincount(inv, weights=mass[sel] * x[sel, 1]) / m
    vx = np.bincount(inv, weights=mass[sel] * v[sel, 0]) / m
    return ids, inv, m, cx, cy, vx


def plot_snapshot(path, out):
    """Two panels: the free-surface region at equal aspect, a few y-periods wide, coloured by the
    velocity along the drive; and the ejecta in (x, vx) phase space, one dot per fragment sized
    and coloured by its mass, so jets (fast, light) and spall layers (slow, heavy) separate."""
    from matplotlib.colors import LogNorm

    snap = mscale.read_snapshot(path)
    x = snap["x"]
    v = snap["v"] if "v" in snap else np.zeros_like(x)
    mass = snap["mass"]
    frag = (snap["fragment"] if "fragment" in snap else np.zeros(len(x), int)).astype(np.int64)
    t = snap.time
    period = snap.attrs.get("period_y", 0.0)
    f_r0 = snap.attrs.get("r0", 0.0)
    ids, inv, m, cx, cy, vx = fragment_table(x, v, mass, frag)
    if period > 0:  # failed particles leave the strip: back into one period for the picture
        x = x.copy()
        x[:, 1] = np.mod(x[:, 1], period)
    bulk = ids[np.argmax(m)] if len(ids) else -2
    in_bulk = frag == bulk
    ymin, ymax = x[:, 1].min(), x[:, 1].max()
    width = period if period > 0 else max(ymax - ymin, 1e-12)
    r0 = f_r0 if f_r0 > 0 else width / 50
    # the region around the bulk's free surface: one y-width behind it, 1.5 ahead; a periodic
    # strip is drawn over two periods so the panel is not a sliver
    fs = x[in_bulk, 0].max() if in_bulk.any() else x[:, 0].max()
    lo, hi = fs - 1.0 * width, fs + 1.5 * width
    # jets still attached to the bulk (a model without fracture) reach further than a width
    # beyond its surface: keep the surface in view (the bulk's x below which 95 % of it lies)
    if in_bulk.sum() > 20:
        lo = min(lo, np.quantile(x[in_bulk, 0], 0.95) - 0.5 * width)
    copies = 2 if period > 0 else 1
    fig = plt.figure(figsize=(13, 5.2))
    gs = fig.add_gridspec(1, 2, width_ratios=[1.2, 1])
    a1, a2 = fig.add_subplot(gs[0]), fig.add_subplot(gs[1])
    near = (x[:, 0] >= lo) & (x[:, 0] <= hi)
    # marker diameter ~ the particle spacing on the page (points; the panel is ~6 in wide)
    s = max(0.3, (0.9 * r0 / (hi - lo) * 6.0 * 72) ** 2)
    for k in range(copies):
        sc = a1.scatter(1e4 * (x[near, 0] - fs), 1e4 * (x[near, 1] + k * period), s=s,
                        c=v[near, 0], cmap="viridis", lw=0, vmin=v[:, 0].min(), vmax=v[:, 0].max())
        piston = (frag < 0) & near
        a1.scatter(1e4 * (x[piston, 0] - fs), 1e4 * (x[piston, 1] + k * period), s=s, c="k", lw=0)
    a1.set_xlim(1e4 * (lo - fs), 1e4 * (hi - fs))
    a1.set_ylim(1e4 * ymin, 1e4 * (ymin + copies * width))
    a1.set_aspect("equal")
    a1.set_xlabel("x − x_free surface [um]")
    a1.set_ylabel("y [um]" + (" (periodic: two periods)" if copies > 1 else ""))
    a1.set_title(f"{time_label(t, snap.time_unit)}: the free surface")
    fig.colorbar(sc, ax=a1, label="vx [km/s]", fraction=0.046, pad=0.02)
    if ((frag < 0) & near).any():  # the driven rows, named in a legend rather than the title
        a1.scatter([], [], s=20, c="k", lw=0, label="driven layer (piston)")
        a1.legend(loc="lower left", fontsize=8, framealpha=0.8)
    det = ids != bulk
    m = 1e9 * m  # fragment masses in ng (docs/output.md: the plots' units)
    if det.any():
        size = 8 + 120 * (m[det] / m[det].max()) ** (1 / 3)
        pc = a2.scatter(1e4 * (cx[det] - fs), vx[det], s=size, c=m[det], cmap="plasma",
                        norm=LogNorm(vmin=m[det].min(), vmax=max(m[det].max(), 1.0001 * m[det].min())),
                        edgecolor="k", lw=0.3)
        cb = fig.colorbar(pc, ax=a2, label="fragment mass [ng]", fraction=0.046, pad=0.02)
        from matplotlib.ticker import FormatStrFormatter  # plain numbers, not 3x10^0
        for axis_fmt in (cb.ax.yaxis.set_major_formatter, cb.ax.yaxis.set_minor_formatter):
            axis_fmt(FormatStrFormatter("%.3g"))
        vb = vx[ids == bulk]
        if len(vb):
            a2.axhline(vb[0], color="0.5", ls="--", lw=1, label=f"largest fragment c.o.m. {vb[0]:.3g} km/s")
            a2.legend(loc="lower right", fontsize=8)
    else:
        a2.text(0.5, 0.5, "no detached fragments yet", ha="center", transform=a2.transAxes)
    a2.set_xlabel("fragment centre − x_free surface [um]")
    a2.set_ylabel("fragment velocity vx [km/s]")
    a2.set_title(f"ejecta: {int(det.sum())} detached fragments, "
                 f"{m[det].sum() if det.any() else 0:.3g} ng")
    a2.grid(True, alpha=0.3)
    fig.tight_layout()
    fig.savefig(out, dpi=110)
    plt.close(fig)
    return out


def plot_run(outdir, plotdir):
    made = plot_drive(outdir, plotdir) + plot_interface(outdir, plotdir)
    for snap in sorted(glob.glob(os.path.join(outdir, "particles_*.h5"))):
        name = os.path.splitext(os.path.basename(snap))[0]
        try:
            # the coupled problem's snapshots (with fragments): every particle problem names
            # its snapshots particles_NNNN.h5, but the free-surface view is the coupled one's
            if "fragment" not in mscale.read_snapshot(snap):
                continue
            made.append(plot_snapshot(snap, os.path.join(plotdir, name + ".png")))
        except (OSError, KeyError) as exc:
            print(f"plot_coupled: {snap}: cannot read ({exc})", file=sys.stderr)
    return made


def main(argv):
    if len(argv) != 2 or argv[1] in ("-h", "--help"):
        print(__doc__)
        return 0 if len(argv) == 2 else 2
    if not os.path.isdir(argv[1]):
        print(f"plot_coupled: '{argv[1]}' is not a directory", file=sys.stderr)
        return 2
    plotdir = os.path.join(argv[1], "plots")
    os.makedirs(plotdir, exist_ok=True)
    for m in plot_run(argv[1], plotdir):
        print(f"plot_coupled: wrote {m}")
    return 0


if __name__ == "__main__":
    sys.exit(main(sys.argv))
