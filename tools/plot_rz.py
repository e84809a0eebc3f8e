#!/usr/bin/python3
# SPDX-License-Identifier: MIT
"""Figures of the Rz80/Rz20 comparison (docs/coupling.md §9, docs/validation.md).

    /usr/bin/python3 tools/plot_rz.py -o docs/img/coupling-rz OUT1:LABEL1 OUT2:LABEL2 ...

For each coupled run directory: the last particle snapshot (coloured by the velocity along the
drive axis; narrow periodic strips are tiled to the same lateral extent for display), and the
detached mass per unit surface area faster than v, against v / u_ref (u_ref: the grid's peak
free-surface velocity, the jet threshold 1.1 u_ref marked), from fragments.csv — the former
velocity split of the coupled run (before the split by shape of coupling/ejecta_split.c; for that
one, tools/rz_split.py). Writes PREFIX-snapshots.png and PREFIX-velocity.png.
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


def last_snapshot(run):
    snap = mscale.Run(run).snapshots[-1]
    return (snap["x"], snap["v"], float(snap.attrs["time"]),
            float(snap.attrs.get("period_y", 0.0)), float(snap.attrs["r0"]))


def f_time(run):
    """End of the particle phase: the time of the last snapshot."""
    return float(mscale.Run(run).snapshots[-1].attrs["time"])


def detached(run):
    """Masses and velocities of the fragments but the bulk (the fragment holding the deepest
    particle of the last snapshot, as the former velocity split chose it) and u_ref."""
    r = mscale.Run(run)
    f = r.fragments
    fs = r.histories["free_surface"]
    snap = r.snapshots[-1]
    fid, x = snap["fragment"], snap["x"][:, 0]
    ok = fid >= 0
    bulk = fid[ok][np.argmin(x[ok])]
    keep = f["id"] != bulk
    # u_ref: the first peak of the grid's free-surface velocity, as the run computes it
    u = fs["u"][fs["t"] <= f_time(run)]
    u = u[u >= 0.05 * u.max()]
    uref = 0.0
    for x in u:
        if x < 0.9 * uref:
            break
        uref = max(uref, x)
    return f["mass"][keep], f["vx"][keep], uref


def main():
    ap = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    ap.add_argument("runs", nargs="+", help="RUNDIR:LABEL")
    ap.add_argument("-o", "--out", required=True, help="output prefix")
    ap.add_argument("--vmax", type=float, default=2.5, help="colour scale top [km/s]")
    a = ap.parse_args()
    runs = [r.split(":", 1) if ":" in r else (r, os.path.basename(r)) for r in a.runs]

    fig, axs = plt.subplots(1, len(runs), figsize=(2.6 * len(runs), 6.5), squeeze=False)
    span = 0.0
    data = []
    for run, label in runs:
        x, v, t, py, r0 = last_snapshot(run)
        data.append((x, v, t, py, r0, label))
        span = max(span, py)
    sc = None
    for ax, (x, v, t, py, r0, label) in zip(axs[0], data):
        tiles = max(1, int(round(span / py))) if py > 0 else 1
        for k in range(tiles):
            sc = ax.scatter((x[:, 1] + k * py) * 1e4, x[:, 0] * 1e4, c=v[:, 0], s=0.3 * (r0 / 2e-4),
                            cmap="jet", vmin=0, vmax=a.vmax, linewidths=0)
        # frame the bulk of the mass (the fastest 0.1 % — single-cluster dust — may fly off it)
        ax.set_ylim(x[:, 0].min() * 1e4 - 20, np.quantile(x[:, 0], 0.999) * 1e4 + 60)
        note = f" (tiled x{tiles})" if tiles > 1 else ""
        ax.set_title(f"{label}\nt = {10 * t:.2f} us{note}", fontsize=9)
        ax.set_xlabel("y [um]")
        ax.set_aspect("equal")
    axs[0][0].set_ylabel("x [um]")
    fig.colorbar(sc, ax=axs[0].tolist(), label="v_x [km/s]", shrink=0.8)
    fig.savefig(a.out + "-snapshots.png", dpi=90)
    print(f"plot_rz: wrote {a.out}-snapshots.png")

    fig, ax = plt.subplots(figsize=(7, 4.5))
    for (run, label), (x, v, t, py, r0, _) in zip(runs, data):
        m, vx, uref = detached(run)
        area = py * r0  # plane-strain cross-section: periodic width x thickness h = a
        if len(m) == 0:
            ax.plot([], [], label=f"{label}: nothing detached")
            continue
        order = np.argsort(vx)[::-1]
        ax.step(vx[order] / uref, np.cumsum(m[order]) / area, where="post", label=label)
    ax.axvline(1.1, color="k", ls="--", lw=0.8)
    ax.set_yscale("log")
    ax.text(1.12, 0.95, "jets ->", fontsize=8, transform=ax.get_xaxis_transform())
    ax.set_xlabel("fragment velocity / grid free-surface jump-off velocity")
    ax.set_ylabel("detached mass faster than v [g/cm^2]")
    ax.legend(fontsize=8)
    ax.grid(alpha=0.3)
    fig.tight_layout()
    fig.savefig(a.out + "-velocity.png", dpi=90)
    print(f"plot_rz: wrote {a.out}-velocity.png")


if __name__ == "__main__":
    main()
