#!/usr/bin/python3
# SPDX-License-Identifier: MIT
"""Plots of a `cluster_dynamics` or `discrete_model` run: energies and binned profiles.

Usage: /usr/bin/python3 tools/plot_particles.py RUNDIR        # PNGs into RUNDIR/plots/

  energy.png     every term of cd_energy.csv / dm_energy.csv against time, and the relative
                 drift of the total (the balance the model conserves)
  profiles.png   cd_profiles.csv: density, velocity, stress and sigma_u against x, one line per
                 output time (colour = time), with the tracked shock front of cd_front.csv
  dm_profiles.png  dm_profile_NNN.csv: the model against the exact solution where known
Also offers plot_run(outdir, plotdir) for tools/plot_run.py. Debian's numpy/matplotlib only.
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


def plot_energy(outdir, plotdir):
    path = next((p for p in (os.path.join(outdir, "cd_energy.csv"),
                             os.path.join(outdir, "dm_energy.csv")) if os.path.exists(p)), None)
    if not path:
        return []
    c, u, title = read_csv(path)
    t = mscale.to_us(c["t"], c.unit("t"))
    terms = [n for n in c if n not in ("t", "px", "py", "pz", "v_free_surface", "hourglass",
                                       "total")]
    fig, (a1, a2) = plt.subplots(1, 2, figsize=(12, 4.4))
    for n in terms:
        a1.plot(t, c[n], label=lab(n, u))
    if "total" in c:
        a1.plot(t, c["total"], "k--", lw=1, label=lab("total", u))
        ref = max(np.abs(c[n]).max() for n in terms) if terms else 1.0
        a2.plot(t, (c["total"] - c["total"][0]) / (ref if ref > 0 else 1.0))
        a2.set_ylabel("(total − total(0)) / largest term")
        a2.set_title("energy balance drift")
    elif "hourglass" in c:
        a2.plot(t, c["hourglass"])
        a2.set_ylabel("zero-energy-mode indicator [1]")
        a2.set_title("zero-energy modes")
    for ax in (a1, a2):
        ax.set_xlabel("t [us]")
        ax.grid(True, alpha=0.3)
    a1.set_title(title if len(title) < 70 else title[:67] + "...", fontsize=9)
    a1.legend(fontsize=7)
    fig.tight_layout()
    out = os.path.join(plotdir, "energy.png")
    fig.savefig(out, dpi=120)
    plt.close(fig)
    return [out]


def plot_cd_profiles(outdir, plotdir):
    path = os.path.join(outdir, "cd_profiles.csv")
    if not os.path.exists(path):
        return []
    c, u, _ = read_csv(path)
    times = np.unique(c["t"])
    if len(times) == 0:
        return []
    fields = [n for n in ("rho", "vx", "Pxx", "sigma_u") if n in c]
    fig, axs = plt.subplots(1, len(fields), figsize=(4.2 * len(fields), 4))
    axs = np.atleast_1d(axs)
    cmap = plt.get_cmap("viridis")
    front = None
    fpath = os.path.join(outdir, "cd_front.csv")
    if os.path.exists(fpath):
        front, _, _ = read_csv(fpath)
    for k, tk in enumerate(times):
        sel = c["t"] == tk
        col = cmap(k / max(len(times) - 1, 1))
        for ax, n in zip(axs, fields):
            ax.plot(c["x"][sel], c[n][sel], color=col, lw=1,
                    label=f"t = {mscale.to_us(tk, c.unit('t')):.3g} us" if n == fields[0]
                    else None)
    for ax, n in zip(axs, fields):
        ax.set_xlabel(lab("x", u))
        ax.set_ylabel(lab(n, u))
        ax.grid(True, alpha=0.3)
        if front is not None:
            ok = np.isfinite(front["front"])
            for xf in front["front"][ok][-1:]:
                ax.axvline(xf, color="r", ls=":", lw=1)
    axs[0].legend(fontsize=7)
    axs[0].set_title("binned profiles (red: last shock front)")
    fig.tight_layout()
    out = os.path.join(plotdir, "profiles.png")
    fig.savefig(out, dpi=120)
    plt.close(fig)
    return [out]


def plot_dm_profiles(outdir, plotdir):
    files = sorted(glob.glob(os.path.join(outdir, "dm_profile_*.csv")))
    if not files:
        return []
    fig, ax = plt.subplots(figsize=(7.5, 4.5))
    cmap = plt.get_cmap("viridis")
    for k, path in enumerate(files):
        c, u, title = read_csv(path)
        # the exact column is sigma_xx (contact) or w_x (rod): plot the field it describes
        cand = [n for n in ("sigma_xx", "w_x") if n in c]
        has_exact = "exact" in c and np.any(c["exact"])
        field = (min(cand, key=lambda n: np.abs(c[n] - c["exact"]).sum()) if has_exact
                 else cand[0])
        order = np.argsort(c["x"])
        col = cmap(k / max(len(files) - 1, 1))
        ax.plot(c["x"][order], c[field][order], ".", ms=2, color=col,
                label=f"{field}: {os.path.basename(path)}")
        if has_exact:
            ax.plot(c["x"][order], c["exact"][order], "k-", lw=0.8,
                    label="exact" if k == 0 else None)
        ax.set_ylabel(lab(field, u))
    ax.set_xlabel("x [cm]")
    ax.set_title("discrete model against the exact solution")
    ax.grid(True, alpha=0.3)
    ax.legend(fontsize=7)
    fig.tight_layout()
    out = os.path.join(plotdir, "dm_profiles.png")
    fig.savefig(out, dpi=120)
    plt.close(fig)
    return [out]


def plot_run(outdir, plotdir):
    return plot_energy(outdir, plotdir) + plot_cd_profiles(outdir, plotdir) + plot_dm_profiles(
        outdir, plotdir)


def main(argv):
    if len(argv) != 2 or argv[1] in ("-h", "--help"):
        print(__doc__)
        return 0 if len(argv) == 2 else 2
    plotdir = os.path.join(argv[1], "plots")
    os.makedirs(plotdir, exist_ok=True)
    for m in plot_run(argv[1], plotdir):
        print(f"plot_particles: wrote {m}")
    return 0


if __name__ == "__main__":
    sys.exit(main(sys.argv))
