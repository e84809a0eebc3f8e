#!/usr/bin/python3
# SPDX-License-Identifier: MIT
"""Plot fragment spectra, size/velocity distributions and detector arrivals (docs/coupling.md).

Usage:
  /usr/bin/python3 tools/plot_spectrum.py RUNDIR            # PNGs into RUNDIR/plots/
  /usr/bin/python3 tools/plot_spectrum.py SPECTRUM.csv [-o OUT.png]
                                     # one CSV from `mscale spectrum SNAP.h5 > SPECTRUM.csv`

In a run directory it looks for the coupling outputs by name (any that exist):
  spectrum*.csv          g,count,mass             fragment spectra N(g): one overlay, spectra.png
  fragments*.csv         id,count,mass,d,...      per-fragment table
  cumulative*.csv        mass,N_ge,M_ge           cumulative N(>=m)
  mass_hist*.csv, diameter_hist*.csv  lo,hi,count,mass
  ejecta_velocity*.csv   v,M_ge                   cumulative ejected mass vs velocity
  ejecta_mass.csv        t,M_ej,...,M_jet,M_layer,M_debris  ejected mass and the run's split
                                                  (jets / spall layers / debris) vs time
  arrivals.csv           id,mass,d,t_arrival,...  fragments at the detector plane
Also offers plot_run(outdir, plotdir) for tools/plot_run.py. Debian's numpy/matplotlib only.
"""
import glob
import os
import sys

import matplotlib

matplotlib.use("Agg")
import matplotlib.pyplot as plt  # noqa: E402
import numpy as np  # noqa: E402

sys.path.insert(0, os.path.join(os.path.dirname(os.path.abspath(__file__)), "..", "python"))
import mscale  # noqa: E402  (python/mscale: the reader of mscale's outputs)


def read_csv(path):
    """An mscale CSV read by the package (python/mscale): (columns by name, units by name,
    title). The title is the file's first comment line, or its name."""
    t = mscale.read_csv(path)
    return t, t.units, t.title or os.path.basename(path)


def lab(name, units):
    return f"{name} [{units[name]}]" if name in units else name


def plot_spectrum_axes(ax, path):
    c, u, title = read_csv(path)
    if len(c["g"]) == 0:
        ax.text(0.5, 0.5, "no fragments", ha="center", transform=ax.transAxes)
        return
    ax.loglog(c["g"], c["count"], "o", ms=4, label="N(g): fragments of g clusters")
    ax2 = ax.twinx()
    ax2.loglog(c["g"], c["mass"], "s", ms=3, color="tab:red", alpha=0.6, label="mass in size g")
    ax2.set_ylabel(lab("mass", u), color="tab:red")
    ax.set_xlabel("g (clusters per fragment)")
    ax.set_ylabel("N(g)")
    ax.set_title(title if len(title) < 70 else title[:67] + "...", fontsize=9)
    ax.grid(True, which="both", alpha=0.3)


def plot_spectrum_file(path, out):
    fig, ax = plt.subplots(figsize=(6.5, 4.5))
    plot_spectrum_axes(ax, path)
    fig.tight_layout()
    fig.savefig(out, dpi=120)
    plt.close(fig)
    return out


def title_time(table):
    """The time a spectrum CSV's title names ('... t = 0.29 (10us) ...'), in us; None if
    absent."""
    return None if table.time is None else mscale.to_us(table.time, table.time_unit)


def plot_spectra(outdir, plotdir):
    """One picture of every spectrum of a run: N(g) at each snapshot time (colour = time), the
    final one and the detector's; the mass in each size beside it."""
    series = sorted(glob.glob(os.path.join(outdir, "spectrum_[0-9]*.csv")))
    extra = [p for p in (os.path.join(outdir, "spectrum.csv"),
                         os.path.join(outdir, "spectrum_detector.csv")) if os.path.exists(p)]
    if not series and not extra:
        return []
    fig, (a1, a2) = plt.subplots(1, 2, figsize=(12, 4.6))
    cmap = plt.get_cmap("viridis")
    for k, path in enumerate(series):
        c, u, title = read_csv(path)
        if len(c["g"]) == 0:
            continue
        t = title_time(c)
        col = cmap(k / max(len(series) - 1, 1))
        lbl = f"t = {t:.3g} us" if t is not None else os.path.basename(path)
        a1.plot(c["g"], c["count"], "o-", ms=3, lw=1, color=col, label=lbl)
        a2.plot(c["g"], c["mass"], "o-", ms=3, lw=1, color=col)
    for path, style, name in zip(extra, ("k--", "r:"), ("end of the particle phase",
                                                         "at the detector")):
        c, u, _ = read_csv(path)
        if len(c["g"]):
            a1.plot(c["g"], c["count"], style, lw=1.6, label=name)
            a2.plot(c["g"], c["mass"], style, lw=1.6)
    for ax in (a1, a2):
        ax.set_xscale("log")
        ax.set_yscale("log")
        ax.set_xlabel("fragment size g [particles]")
        ax.grid(True, which="both", alpha=0.3)
    a1.set_ylabel("number of fragments N(g)")
    a1.set_title("fragment spectrum")
    a1.legend(fontsize=7, ncol=2)
    a2.set_ylabel("mass in fragments of size g [g]")
    a2.set_title("mass by fragment size")
    fig.tight_layout()
    out = os.path.join(plotdir, "spectra.png")
    fig.savefig(out, dpi=120)
    plt.close(fig)
    return [out]


def first(outdir, pattern):
    files = sorted(glob.glob(os.path.join(outdir, pattern)))
    return files[0] if files else None


# Plots give lengths of particles and fragments in um (the snapshots' unit) and ejected masses
# in ng, so no axis carries a 1e-8 offset and the figures of one run agree.
_UM_PER = {"cm": 1e4, "m": 1e6, "mm": 1e3, "um": 1.0}
_NG_PER = {"g": 1e9, "kg": 1e12, "mg": 1e6, "ng": 1.0}


def to_um(values, unit):
    return values * _UM_PER.get(unit, 1.0), "um" if unit in _UM_PER else unit


def to_ng(values, unit):
    return values * _NG_PER.get(unit, 1.0), "ng" if unit in _NG_PER else unit


def plot_distributions(outdir, plotdir):
    mh, dh, cu = (first(outdir, p) for p in ("mass_hist*.csv", "diameter_hist*.csv", "cumulative*.csv"))
    if not (mh or dh or cu):
        return []
    fig, axs = plt.subplots(1, 3, figsize=(14, 4))
    for ax, path, what in ((axs[0], mh, "mass"), (axs[1], dh, "equivalent diameter")):
        if not path:
            ax.set_visible(False)
            continue
        c, u, _ = read_csv(path)
        conv = to_um if what != "mass" else (lambda v, unit: (v, unit))
        lo, unit = conv(c["lo"], u.get("lo", ""))
        hi, _ = conv(c["hi"], u.get("hi", ""))
        if len(c["lo"]):
            ax.bar(lo, c["count"], width=hi - lo, align="edge", edgecolor="k", alpha=0.7)
            ax.set_xscale("log")
        ax.set_xlabel(f"{what} [{unit}]")
        ax.set_ylabel("fragments per bin")
        ax.set_title(f"{what} distribution")
    if cu:
        c, u, _ = read_csv(cu)
        if len(c["mass"]):
            axs[2].loglog(c["mass"], c["N_ge"], "o-", ms=3)
        axs[2].set_xlabel(lab("mass", u))
        axs[2].set_ylabel("N(>= m)")
        axs[2].set_title("cumulative number of fragments")
        axs[2].grid(True, which="both", alpha=0.3)
    else:
        axs[2].set_visible(False)
    fig.tight_layout()
    out = os.path.join(plotdir, "fragment_distributions.png")
    fig.savefig(out, dpi=120)
    plt.close(fig)
    return [out]


def plot_ejecta(outdir, plotdir):
    ev, em = first(outdir, "ejecta_velocity*.csv"), first(outdir, "ejecta_mass.csv")
    if not (ev or em):
        return []
    fig, axs = plt.subplots(1, 2, figsize=(11, 4))
    if ev:
        c, u, _ = read_csv(ev)
        m, mu = to_ng(c["M_ge"], u.get("M_ge", ""))
        if len(c["v"]):
            axs[0].step(c["v"], m, where="post")
        axs[0].set_xlabel(lab("v", u))
        axs[0].set_ylabel(f"ejected mass with velocity >= v [{mu}]")
        axs[0].set_title("cumulative ejected mass vs velocity")
        axs[0].grid(True, alpha=0.3)
    else:
        axs[0].set_visible(False)
    if em:
        c, u, _ = read_csv(em)
        m, mu = to_ng(c["M_ej"], u.get("M_ej", ""))
        t_us = mscale.to_us(c["t"], u.get("t"))
        axs[1].plot(t_us, m, "o-", ms=3, color="k", label="M_ej (all but the largest, ahead)")
        # the run's split (docs/coupling.md "The split"), where the file has it
        for col, colour, what in (("M_jet", "tab:red", "jets (ahead of the foremost layer)"),
                                  ("M_layer", "tab:blue", "spall layers (full-width)"),
                                  ("M_debris", "tab:orange", "debris")):
            if col in c:
                axs[1].plot(t_us, to_ng(c[col], u.get(col, ""))[0], "-", color=colour, label=what)
        if "M_jet" in c:
            axs[1].legend(fontsize=7)
        axs[1].set_xlabel("t [us]")
        axs[1].set_ylabel(f"mass [{mu}]")
        axs[1].set_title("ejected mass and the run's split vs time")
        axs[1].grid(True, alpha=0.3)
    else:
        axs[1].set_visible(False)
    fig.tight_layout()
    out = os.path.join(plotdir, "ejecta.png")
    fig.savefig(out, dpi=120)
    plt.close(fig)
    return [out]


def plot_arrivals(outdir, plotdir):
    ar = first(outdir, "arrivals.csv")
    if not ar:
        return []
    c, u, title = read_csv(ar)
    fig, axs = plt.subplots(1, 3, figsize=(15, 4))
    t_us, d_um = mscale.to_us(c["t_arrival"], u["t_arrival"]), to_um(c["d"], u.get("d", "cm"))[0]
    m_ng, mu = to_ng(c["mass"], u.get("mass", "g"))
    if len(t_us):
        axs[0].hist(t_us, bins=min(40, max(5, len(t_us))), weights=m_ng, edgecolor="k",
                    alpha=0.7)
        sc = axs[1].scatter(t_us, c["vx"], c=d_um, s=10, cmap="viridis")
        fig.colorbar(sc, ax=axs[1], label="equivalent diameter [um]")
        wide = d_um.max() > 10 * d_um.min()  # log axes only over more than a decade
        bins = (np.logspace(np.log10(d_um.min()), np.log10(d_um.max()) + 1e-9, 30) if wide
                else np.linspace(d_um.min() * 0.95, d_um.max() * 1.05 + 1e-12, 12))
        axs[2].hist(d_um, bins=bins, edgecolor="k", alpha=0.7)
        if wide:
            axs[2].set_xscale("log")
    axs[0].set_xlabel("arrival time [us]")
    axs[0].set_ylabel(f"mass per bin [{mu}]")
    axs[0].set_title(f"arrivals at the detector: {len(t_us)} fragments, {m_ng.sum():.3g} {mu}")
    axs[1].set_xlabel("arrival time [us]")
    axs[1].set_ylabel(lab("vx", u))
    axs[1].set_title("arrival velocity")
    axs[2].set_xlabel("equivalent diameter [um]")
    axs[2].set_ylabel("fragments")
    axs[2].set_title("sizes at the detector")
    fig.tight_layout()
    out = os.path.join(plotdir, "arrivals.png")
    fig.savefig(out, dpi=120)
    plt.close(fig)
    return [out]


def plot_run(outdir, plotdir):
    """Every coupling plot that the run directory has data for; returns the PNG paths."""
    made = plot_spectra(outdir, plotdir)
    made += plot_distributions(outdir, plotdir)
    made += plot_ejecta(outdir, plotdir)
    made += plot_arrivals(outdir, plotdir)
    return made


def main(argv):
    if len(argv) < 2 or argv[1] in ("-h", "--help"):
        print(__doc__)
        return 0 if len(argv) >= 2 else 2
    target = argv[1]
    out = None
    if len(argv) == 4 and argv[2] == "-o":
        out = argv[3]
    elif len(argv) != 2:
        print(__doc__, file=sys.stderr)
        return 2
    try:
        if os.path.isdir(target):
            plotdir = os.path.join(target, "plots")
            os.makedirs(plotdir, exist_ok=True)
            made = plot_run(target, plotdir)
        elif os.path.isfile(target):
            made = [plot_spectrum_file(target, out or os.path.splitext(target)[0] + ".png")]
        else:
            print(f"plot_spectrum: '{target}' does not exist", file=sys.stderr)
            return 2
    except (ValueError, KeyError) as exc:
        print(f"plot_spectrum: {target}: cannot read ({exc})", file=sys.stderr)
        return 2
    for m in made:
        print(f"plot_spectrum: wrote {m}")
    if not made:
        print(f"plot_spectrum: nothing to plot in {target}")
    return 0


if __name__ == "__main__":
    sys.exit(main(sys.argv))
