#!/usr/bin/python3
# SPDX-License-Identifier: MIT
"""Richtmyer–Meshkov microjets of the discrete model: the tables of bench_dm_jets as plots.

Usage:  /usr/bin/python3 tools/plot_jets.py OUTDIR [-o FILE.png]

Reads OUTDIR/jets_kh0.csv (spike-tip velocity vs k h0, one row per case and resolution) and,
if present, OUTDIR/jets_strength.csv (arrested growth vs the yield stress), both written by
build/bench/dm_jets/bench_dm_jets -o OUTDIR (docs/validation.md "Microjets"). Left: the
spike velocity over the free surface, v_spike / (k a0+ du), and the amplitude's rate v_eta /
(k a0+ du) against k h0 per resolution, with
Richtmyer's impulsive prediction (1) and the 10 % band; the peak and late slopes as the
bars' ends. Right: k (eta_max - eta_b) against Y on log-log axes, with the fitted power law
and slope -1. Also prints the fit. Writes OUTDIR/jets.png unless -o is given.
Needs Debian's numpy and matplotlib (run with /usr/bin/python3).
"""
import argparse
import os
import sys

import matplotlib
matplotlib.use("Agg")
import matplotlib.pyplot as plt  # noqa: E402
import numpy as np  # noqa: E402

sys.path.insert(0, os.path.join(os.path.dirname(os.path.abspath(__file__)), "..", "python"))
import mscale  # noqa: E402  (python/mscale: the reader of mscale's outputs)


def strength_fit(t):
    """Power law k deta_max ~ Y^slope over the strength-limited, resolved cases: arrested,
    Y > 0, k deta_max < 1 (beyond, the growth is nonlinear) and deta_max >= 3 spacings.
    Returns (slope, C of k deta = C rho v_lin0^2 / Y (geometric mean), mask)."""
    y = t["Y"]
    h = t["lambda"] / t["ncol"]
    keep = (y > 0) & (t["arrested"] > 0) & (t["k_deta"] < 1) & (t["deta_max"] >= 3 * h)
    if keep.sum() < 2:
        return None, None, keep
    slope = np.polyfit(np.log(y[keep]), np.log(t["k_deta"][keep]), 1)[0]
    # k deta = C rho v^2 / (Y): C from the geometric mean over the arrested points
    const = np.exp(np.mean(np.log(t["k_deta"][keep] / t["rho_v2_over_kY"][keep])))
    return slope, const, keep


def plot_jets(outdir, output=None):
    """Draw OUTDIR/jets.png (or output); returns its path."""
    kpath = os.path.join(outdir, "jets_kh0.csv")
    spath = os.path.join(outdir, "jets_strength.csv")
    kh = mscale.read_csv(kpath) if os.path.exists(kpath) else None
    st = mscale.read_csv(spath) if os.path.exists(spath) else None
    if kh is None and st is None:
        raise SystemExit(f"{outdir}: neither jets_kh0.csv nor jets_strength.csv")
    npan = (kh is not None) + (st is not None)
    fig, axes = plt.subplots(1, npan, figsize=(5.5 * npan + 0.5, 4.5), squeeze=False)
    axes = list(axes[0])
    if kh is not None:
        plot_kh0(axes[0], kh)
    if st is not None:
        plot_strength(axes[-1], st)
    fig.tight_layout()
    out = output or os.path.join(outdir, "jets.png")
    fig.savefig(out, dpi=120)
    plt.close(fig)
    return out


def plot_kh0(ax, kh):
    """Spike and amplitude velocities over the impulsive prediction, per resolution."""
    for ncol in np.unique(kh["ncol"]):
        m = kh["ncol"] == ncol
        x, r = kh["kh0"][m], kh["ratio"][m]
        lo = kh["v_spike_late"][m] / kh["v_lin"][m]
        hi = kh["v_spike_peak"][m] / kh["v_lin"][m]
        eb = ax.errorbar(x, r, yerr=[np.clip(r - lo, 0, None), np.clip(hi - r, 0, None)],
                         marker="o", capsize=3, label=f"spike axis, lambda = {int(ncol)} h")
        ax.plot(x, kh["v_eta"][m] / kh["v_lin"][m], "--^", ms=4, color=eb[0].get_color(),
                label=f"amplitude (spike - bubble)/2, lambda = {int(ncol)} h")
    xx = np.linspace(0, max(kh["kh0"]) * 1.05, 50)
    ax.plot(xx, np.ones_like(xx), "k-", lw=1, label="impulsive k a0+ du [Richtmyer1960]")
    ax.fill_between(xx, 0.9, 1.1, color="0.85", label="10 %")
    ax.set_xlabel("k h0")
    ax.set_ylabel("(v_spike - u_fs) / (k a0+ du)")
    ax.set_title("spike tip over the free surface (bars: peak, late)")
    ax.legend(fontsize=8)


def plot_strength(ax, st):
    """Arrested growth vs Y (log-log) with the fit of strength_fit."""
    slope, const, keep = strength_fit(st)
    y = st["Y"]
    pos = y > 0
    arr = st["arrested"] > 0
    ax.loglog(y[pos & keep], st["k_deta"][pos & keep], "o",
              label="strength-limited (k deta < 1, >= 3 spacings): fitted")
    if (pos & arr & ~keep).any():
        ax.loglog(y[pos & arr & ~keep], st["k_deta"][pos & arr & ~keep], "s", mfc="none",
                  label="arrested, not in the fit")
    if (pos & ~arr).any():
        ax.loglog(y[pos & ~arr], st["k_deta"][pos & ~arr], "x",
                  label="not arrested in the run (lower bound)")
    if slope is not None:
        yy = np.geomspace(y[keep].min(), y[keep].max(), 20)
        scale = st["rho_v2_over_kY"][keep][0] * y[keep][0]
        ax.loglog(yy, const * scale / yy, "k--",
                  label=f"C rho v0^2/(kY), C = {const:.3g}; fitted slope {slope:.2f}")
        print(f"strength: log-log slope {slope:.3f}, k deta_max = {const:.4g} rho v0^2/Y "
              f"over {int(keep.sum())} arrested cases")
    ax.set_xlabel(f"Y [{st.units.get('Y', 'GPa')}]")
    ax.set_ylabel("k (eta_max - eta_b)")
    ax.set_title(f"growth arrested by strength, k h0 = {st['kh0'][0]:g}")
    ax.legend(fontsize=8)


def main(argv=None):
    p = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    p.add_argument("outdir")
    p.add_argument("-o", "--output")
    a = p.parse_args(argv)
    print(plot_jets(a.outdir, a.output))


if __name__ == "__main__":
    main()
