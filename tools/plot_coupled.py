#!/usr/bin/python3
"""Plots of a `coupled` run (docs/coupling.md): the drive and the particle snapshots.

Usage: /usr/bin/python3 tools/plot_coupled.py RUNDIR        # PNGs into RUNDIR/plots/

  drive.png              U(t) of the drive node (history_<tag>.csv of the grid) and the
                         free-surface velocity of the grid vs the particles (free_surface.csv)
  interface.png          two-way runs: interface and free-surface velocities, interface
                         impulse and work as the grid gave and the particles received them
  particles_NNNN.png     particle snapshots (particles_NNNN.h5) coloured by fragment, with the
                         velocity along the drive axis in a second panel
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
    a2.set_ylabel("per cm^2 (GPa*10us, kJ/cm^2)")
    a2.set_title("interface balance")
    a2.grid(True, alpha=0.3)
    a2.legend(fontsize=8)
    fig.tight_layout()
    out = os.path.join(plotdir, "interface.png")
    fig.savefig(out, dpi=120)
    plt.close(fig)
    return [out]


def plot_snapshot(path, out):
    import h5py

    with h5py.File(path, "r") as f:
        x = f["particles/x"][...]
        v = f["particles/v"][...] if "particles/v" in f else np.zeros_like(x)
        frag = f["particles/fragment"][...] if "particles/fragment" in f else np.zeros(len(x), int)
        t = f["particles"].attrs.get("time", np.nan)
    fig, (a1, a2) = plt.subplots(1, 2, figsize=(13, 5), sharey=True)
    # fragment colours: the bulk (largest) grey, the others cycled through a qualitative map
    ids, counts = np.unique(frag[frag >= 0], return_counts=True)
    bulk = ids[np.argmax(counts)] if len(ids) else -2
    col = np.where(frag == bulk, 0.0, (frag % 20 + 1) / 21.0)
    cmap = plt.get_cmap("tab20").copy()
    s = max(0.2, min(4.0, 2e4 / max(len(x), 1)))
    a1.scatter(x[frag == bulk, 0], x[frag == bulk, 1], s=s, c="0.6", lw=0)
    other = (frag != bulk) & (frag >= 0)
    a1.scatter(x[other, 0], x[other, 1], s=s, c=col[other], cmap=cmap, vmin=0, vmax=1, lw=0)
    a1.scatter(x[frag < 0, 0], x[frag < 0, 1], s=s, c="k", lw=0)
    a1.set_title(f"t = {t:.4g} (10 us): {len(ids)} fragments (grey: bulk, black: piston)")
    a1.set_xlabel("x [cm]")
    a1.set_ylabel("y [cm]")
    a1.set_aspect("equal")
    sc = a2.scatter(x[:, 0], x[:, 1], s=s, c=v[:, 0], cmap="viridis", lw=0)
    fig.colorbar(sc, ax=a2, label="vx [km/s]")
    a2.set_title("velocity along the drive axis")
    a2.set_xlabel("x [cm]")
    a2.set_aspect("equal")
    fig.tight_layout()
    fig.savefig(out, dpi=110)
    plt.close(fig)
    return out


def plot_run(outdir, plotdir):
    made = plot_drive(outdir, plotdir) + plot_interface(outdir, plotdir)
    for snap in sorted(glob.glob(os.path.join(outdir, "particles_*.h5"))):
        name = os.path.splitext(os.path.basename(snap))[0]
        try:
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
