#!/usr/bin/python3
# SPDX-License-Identifier: MIT
"""Jets vs spall layers in a grooved coupled run's last snapshot (docs/validation.md, issue 21).

    /usr/bin/python3 tools/rz_split.py [--png FILE] OUT [OUT ...]

The split of the detached material by shape, per unit surface area (g/cm^2; the cross-section
is the periodic width times the plane-strain thickness: 1 cm for the discrete model, a for
cluster dynamics), recomputed from the last snapshot: the definition of the run's own split
(coupling/ejecta_split.c, docs/coupling.md §9 "The split"), written independently, so that the
two check each other (the run's numbers are the last row of its ejecta_mass.csv, printed beside):

* a fragment is full-width when its particles occupy at least 90 % of the lateral bins of width
  a across the period (a spalled layer spans the periodic width; an intact layer leaves no bin
  empty, a torn one may leave a few). The deepest full-width fragment is the bulk (what stays on
  the piston) if its deepest particle lies within 2 spacings of the deepest particle of all (a
  lone failed particle at the piston does not make the slab detached; a thicker failed zone
  beneath it does: then it is a layer and there is no bulk); the other full-width fragments are
  layers.
* The level is one spacing above the largest, over the full-width fragments, of the median over
  the lateral bins of the fragment's front particle. Detached particles beyond the level are "ahead" (jets and
  the debris in front of the layers: the run's M_jet), split here into those within a quarter
  groove period of a valley's axis (at half a period from the profile's peaks) and the rest
  (crest debris); detached particles below it are "layer" (M_layer) or "behind" (M_debris).
  Without a level every detached particle is "behind".
* The depth of the first spall plane: the deepest initial position (first snapshot, by gid) of
  the foremost layer's particles below the initial crest tops.

With --png, the last snapshot of each run is drawn coloured by that class.

With --coverage, every snapshot of each run is also read with a level that does not need a
connected layer: the top of the foremost slice 2 spacings thick in which particles (of any
fragment) occupy at least 90 % of the lateral bins. A layer broken sideways into chunks still
covers the width, so this level survives the break-up that leaves the run's split without a
full-width fragment (every detached piece then counts as debris); the mass more than one
spacing beyond it is printed per unit area, split at the valleys as above, and as a fraction of
the region's mass.

With --failed FILE, every snapshot of the first run is drawn with the particles that are a
fragment of their own (failed particles: the discrete model's failed particle is its own
fragment) in red: where the slab fails, and when.
"""
import argparse
import os
import sys

import numpy as np

sys.path.insert(0, os.path.join(os.path.dirname(os.path.abspath(__file__)), "..", "python"))
import mscale  # noqa: E402  (python/mscale: the reader of mscale's outputs)

COVER = 0.9  # lateral coverage of a layer (see the docstring)
REACH = 2.0  # spacings between the deepest particle and the bulk's


def thickness(run, r0):
    """Plane-strain thickness: 1 cm for the discrete model's 2D region, a for cluster dynamics."""
    with open(os.path.join(run, "deck.resolved.yaml")) as f:
        return 1.0 if "model: discrete_model" in f.read() else r0


def u_ref(run, t_end):
    """The grid's free-surface jump-off velocity: its first peak, as the run computes it."""
    fs = mscale.Run(run).histories["free_surface"]
    u = fs["u"][fs["t"] <= t_end]
    u = u[u >= 0.05 * u.max()]
    ref = 0.0
    for x in u:
        if x < 0.9 * ref:
            break
        ref = max(ref, x)
    return ref


def wavelength(run):
    """The groove period (the deck's `surface: wavelength`), or 0 without one."""
    with open(os.path.join(run, "deck.resolved.yaml")) as f:
        for line in f:
            if line.strip().startswith("wavelength:"):
                return float(line.split(":")[1].split("#")[0])
    return 0.0


def valley_phase(lam):
    """Lateral position of a groove valley, modulo the period lam: the regions build the sine
    profile as a drop of depth (1 - cos 2 pi y / lam) / 2 below the peaks at y = lo
    (particles/dm/dm_region.c surface_drop, particles/cd/cd_region.c), so the valleys lie at
    lam / 2. (Read from the deck, not from a snapshot: after breakout a valley carries the jet
    and no longer has the lowest front.)"""
    return 0.5 * lam


def coverage_level(x, y, lo, period, r0, nbin):
    """Top of the foremost 2-spacing slice whose particles occupy >= COVER of the lateral bins."""
    xs = np.floor(x / (2 * r0)).astype(int)
    b = np.floor(((y - lo) % period) / period * nbin).astype(int)
    occupied = np.unique(np.stack([xs, b]), axis=1)  # distinct (slice, bin) pairs
    sl, count = np.unique(occupied[0], return_counts=True)
    full = sl[count >= COVER * nbin]
    return (full.max() + 1) * 2 * r0 if full.size else np.nan


def coverage_history(run):
    """Per snapshot: (t, level, ahead, ahead at the valleys, ahead / region mass); see --coverage."""
    r = mscale.Run(run)
    first = r.snapshots[0]
    r0, period = float(first.attrs["r0"]), float(first.attrs["period_y"])
    lo = float(first.attrs.get("lo_y", 0.0))
    nbin = max(1, int(round(period / r0)))
    area = period * thickness(run, r0)
    lam = wavelength(run) or period
    y0 = valley_phase(lam)
    rows = []
    for snap in r.snapshots:
        x, y, m = snap["x"][:, 0], snap["x"][:, 1], snap["mass"]
        x_c = coverage_level(x, y, lo, period, r0, nbin)
        ahead = x > x_c + r0 if np.isfinite(x_c) else np.zeros(x.size, bool)
        dist = np.abs((y - lo - y0 + 0.5 * lam) % lam - 0.5 * lam)
        rows.append((float(snap.attrs["time"]), x_c, m[ahead].sum() / area,
                     m[ahead & (dist < 0.25 * lam)].sum() / area, m[ahead].sum() / m.sum()))
    return rows


def split(run):
    r = mscale.Run(run)
    snap = r.snapshots[-1]
    x, y, v, m = snap["x"][:, 0], snap["x"][:, 1], snap["v"][:, 0], snap["mass"]
    fid = snap["fragment"]
    t = float(snap.attrs["time"])
    r0, period = float(snap.attrs["r0"]), float(snap.attrs["period_y"])
    lo = float(snap.attrs.get("lo_y", 0.0))
    area = period * thickness(run, r0)
    ok = fid >= 0
    nbin = max(1, int(round(period / r0)))
    ids = np.unique(fid[ok])
    cls = {}
    info = {}
    for k in ids:
        s = fid == k
        mk = m[s].sum()
        vk = (m[s] * v[s]).sum() / mk
        bins = np.unique(np.floor(((y[s] - lo) % period) / period * nbin).astype(int))
        info[k] = (mk, vk, x[s].min())
        cls[k] = "layer" if bins.size >= COVER * nbin else "piece"
    # the bulk: the deepest full-width fragment if it reaches within REACH spacings of the deepest
    # particle (what stays on the piston; a lone failed particle next to the piston does not make
    # the slab a layer, a thicker failed zone beneath it does); else none
    full = [k for k in ids if cls[k] == "layer"]
    bulk = min(full, key=lambda k: info[k][2]) if full else None
    if bulk is not None and info[bulk][2] > x[ok].min() + REACH * r0:
        bulk = None
    if bulk is not None:
        cls[bulk] = "bulk"

    # the level of a full-width fragment: the median over the lateral bins of its front particle
    def level(sel):
        b = np.floor(((y[sel] - lo) % period) / period * nbin).astype(int)
        front = np.full(nbin, -np.inf)
        np.maximum.at(front, b, x[sel])
        return np.median(front[np.isfinite(front)])

    layers = [k for k in ids if cls[k] == "layer"]
    x_l = max(level(fid == k) for k in full) + r0 if full else np.nan  # + a row's roughness
    ur = u_ref(run, t)
    out = dict(t=t, u_ref=ur, area=area, x_l=x_l,
               bulk=info[bulk][0] / area if bulk is not None else 0.0, v_max=-np.inf)
    for k in ids:
        if k != bulk:
            out["v_max"] = max(out["v_max"], info[k][1])
    # the run's own split: the ejecta_mass.csv row at the snapshot's time
    em = mscale.read_csv(os.path.join(run, "ejecta_mass.csv"))
    row = int(np.argmin(np.abs(em["t"] - t)))
    for col in ("M_jet", "M_layer", "M_debris", "M_bulk"):
        out["run_" + col] = em[col][row] / area if col in em else np.nan
    # per particle: ahead of the foremost layer's level (jets and the debris that leads them),
    # in a layer below it, or in a piece below it
    det = ok & (fid != bulk) if bulk is not None else ok
    lay = np.isin(fid, layers)
    where = np.where(det, "behind", "bulk")
    where[det & lay] = "layer"
    if full:
        where[det & (x > x_l)] = "ahead"
    for key in ("ahead", "layer", "behind"):
        out[key] = m[where == key].sum() / area
    # "ahead" split laterally: within a quarter period of a valley's axis (the jets) or not
    # (the crests' debris)
    lam = wavelength(run) or period
    y0 = valley_phase(lam)
    dist = np.abs((y - lo - y0 + 0.5 * lam) % lam - 0.5 * lam)
    out["ahead_valley"] = m[(where == "ahead") & (dist < 0.25 * lam)].sum() / area
    out["ahead_crest"] = out["ahead"] - out["ahead_valley"]
    # depth of the first spall plane: the deepest initial position (first snapshot, by gid) of
    # the foremost layer's particles, below the initial crest tops
    first = r.snapshots[0]
    x0 = dict(zip(first["gid"], first["x"][:, 0]))
    top = max(first["x"][:, 0])
    out["spall_depth"] = np.nan
    if layers:
        front_layer = max(layers, key=lambda k: level(fid == k))
        out["spall_depth"] = top - min(x0[g] for g in snap["gid"][fid == front_layer])
    out["n_layers"] = len(layers)
    return out, ((y - lo) % period, x, where, t)


def draw(png, runs, pics):
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    colour = {"bulk": "0.6", "layer": "tab:blue", "behind": "tab:orange", "ahead": "tab:red"}
    ncol = min(4, len(runs))
    nrow = -(-len(runs) // ncol)
    fig, axes = plt.subplots(nrow, ncol, figsize=(3.2 * ncol, 5 * nrow), squeeze=False)
    for ax in axes.flat[len(runs):]:
        ax.axis("off")
    for ax, run, (y, x, where, t) in zip(axes.flat, runs, pics):
        for key, c in colour.items():
            s = where == key
            ax.scatter(y[s] * 1e4, x[s] * 1e4, c=c, s=0.3, linewidths=0)
        ax.set_title(f"{os.path.basename(run.rstrip('/'))}: t = {t:.2f} us", fontsize=9)
        ax.set_xlabel("y [um] (periodic)")
        ax.set_ylabel("x [um] (drive axis)")
        ax.set_aspect("equal")
    handles = [plt.Line2D([], [], marker="o", ls="", color=c, label=k) for k, c in colour.items()]
    fig.legend(handles=handles, loc="lower center", ncol=4, fontsize=8)
    fig.tight_layout(rect=(0, 0.03, 1, 1))
    fig.savefig(png, dpi=80)


def draw_failed(png, run):
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    snaps = mscale.Run(run).snapshots
    fig, axes = plt.subplots(1, len(snaps), figsize=(2.4 * len(snaps), 5.5), squeeze=False)
    for ax, snap in zip(axes.flat, snaps):
        x, y, fid = snap["x"][:, 0], snap["x"][:, 1], snap["fragment"]
        ids, count = np.unique(fid, return_counts=True)
        alone = count[np.searchsorted(ids, fid)] == 1
        for sel, c in ((~alone, "tab:blue"), (alone, "tab:red")):
            ax.scatter(y[sel] * 1e4, x[sel] * 1e4, c=c, s=0.6, linewidths=0)
        ax.set_title(f"{float(snap.attrs['time']):.2f} us: {alone.sum()} alone", fontsize=8)
        ax.set_xlabel("y [um]")
        ax.set_aspect("equal")
    axes[0, 0].set_ylabel("x [um] (drive axis)")
    fig.suptitle(f"{os.path.basename(run.rstrip('/'))}: red = a fragment of its own (failed)",
                 fontsize=9)
    fig.tight_layout()
    fig.savefig(png, dpi=80)


def main():
    ap = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    ap.add_argument("runs", nargs="+")
    ap.add_argument("--png", help="draw the last snapshots coloured by class")
    ap.add_argument("--coverage", action="store_true",
                    help="every snapshot read with the coverage level (see the docstring)")
    ap.add_argument("--failed", help="draw every snapshot of the first run, failed particles red")
    a = ap.parse_args()
    pics = []
    print("run,t_us,u_ref,run's split: jets/layers/debris/bulk,bulk,ahead(valley/crest),layers(n),behind,"
          "x_level_um,spall_depth_um,v_max  [g/cm^2, km/s]")
    for run in a.runs:
        o, pic = split(run)
        pics.append(pic)
        print(f"{run},{o['t']:.3f},{o['u_ref']:.3f},{o['run_M_jet']:.3g}/{o['run_M_layer']:.3g}/"
              f"{o['run_M_debris']:.3g}/{o['run_M_bulk']:.3g},"
              f"{o['bulk']:.3g},{o['ahead']:.3g}({o['ahead_valley']:.3g}/{o['ahead_crest']:.3g}),"
              f"{o['layer']:.3g}({o['n_layers']}),{o['behind']:.3g},"
              f"{o['x_l'] * 1e4:.0f},{o['spall_depth'] * 1e4:.0f},{o['v_max']:.3f}")
    if a.coverage:
        print("run,t_us,x_cover_um,ahead,ahead_valley,ahead/region  [g/cm^2]")
        for run in a.runs:
            for t, x_c, ahead, valley, frac in coverage_history(run):
                print(f"{run},{t:.3f},{x_c * 1e4:.0f},{ahead:.3g},{valley:.3g},{frac:.3f}")
    if a.png:
        draw(a.png, a.runs, pics)
    if a.failed:
        draw_failed(a.failed, a.runs[0])


if __name__ == "__main__":
    main()
