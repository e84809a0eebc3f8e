#!/usr/bin/python3
# SPDX-License-Identifier: MIT
"""Final length, footprint and profile of a Taylor rod from an `impact` run (docs/validation.md,
"Taylor anvil test"; docs/input-impact.md), or from a `cluster_dynamics` run (its first region
is the rod; tools/cd_impact.py; h is then the spacing of the fcc layers, r0/√2).

  taylor_profile.py OUTDIR [OUTDIR2 ...] [-o taylor.png] [--exp-length MM --exp-footprint MM]

For body 0 (a cylinder whose axis is the wall normal) of the run's last particle snapshot
(particles_NNNN.h5, the final state; read through python/mscale):

* length L = the axial extent of its particles + h (half a spacing beyond each end layer);
* footprint D = D0 max(r/r0) over its outer particles (initial radius r0 within h/2 of the
  largest): the rod's surface is taken to stretch radially with the outer particles beside it
  (the same definitions as particles/dm/dm_impact.c, which writes them to impact_summary.csv);
* profile: in slices of one spacing along the axis, the surface radius R0 max(r/r0) of the
  outer particles in the slice (the footprint's definition, slice by slice).

Prints L, D, L/L0, D/D0 for every OUTDIR (and the differences to the experiment when given) and
plots the profiles with the experimental final length and footprint. Units: cm in the files,
mm in the printout and the plot. Run with Debian's python (/usr/bin/python3: numpy, matplotlib).
"""
import argparse
import os
import sys

import numpy as np

sys.path.insert(0, os.path.join(os.path.dirname(os.path.abspath(__file__)), "..", "python"))
import mscale  # noqa: E402  (python/mscale: the reader of mscale's outputs)
import cd_impact  # noqa: E402  (a cluster_dynamics run seen as an impact run)


def rod_geometry(run):
    """(h, radius, length, axis, centre) of body 0 from the resolved deck."""
    sec = run.deck["impact"]
    body = sec["bodies"][0]
    if body.get("shape") != "cylinder":
        raise SystemExit(f"{run.path}: body 0 is not a cylinder")
    axis = "xyz".index(body.get("axis", "z"))
    return (float(sec["spacing"]), float(body["radius"]), float(body["length"]), axis,
            np.array(body["center"], dtype=float))


def measure(outdir, snapshot=-1):
    """Length, footprint (cm), the profile (z, r) and the initial geometry of body 0 in the
    run's particle snapshot number `snapshot` (an index into Run.snapshots; -1: the final
    state)."""
    run = cd_impact.as_impact(mscale.Run(outdir), "layer")  # CD: h = the fcc layer spacing
    h, R0, L0, axis, centre = rod_geometry(run)
    if not run.snapshots:
        raise SystemExit(f"{run.path}: no particle snapshots (particles_NNNN.h5)")
    snap = run.snapshots[snapshot]
    sel = np.asarray(snap["body"]) == 0
    q = [(axis + 1) % 3, (axis + 2) % 3]
    cur = np.asarray(snap["x"], float)[sel]
    ref = np.asarray(snap["X0"], float)[sel]
    z = cur[:, axis]
    r = np.hypot(cur[:, q[0]] - centre[q[0]], cur[:, q[1]] - centre[q[1]])
    r0 = np.hypot(ref[:, q[0]] - centre[q[0]], ref[:, q[1]] - centre[q[1]])
    length = z.max() - z.min() + h
    outer = r0 >= r0.max() - 0.5 * h
    footprint = 2.0 * R0 * np.max(r[outer] / r0[outer])
    edges = np.arange(z.min() - 0.5 * h, z.max() + h, h)
    zc, rc = [], []
    stretch = R0 * r / np.maximum(r0, 1e-300)
    for a, b in zip(edges[:-1], edges[1:]):
        m = (z >= a) & (z < b) & outer
        if m.any():
            zc.append(0.5 * (a + b))
            rc.append(stretch[m].max())
    cs = float(run.deck["impact"].get("hourglass", 1.0))
    return dict(h=h, L0=L0, D0=2 * R0, length=length, footprint=footprint, cs=cs,
                model="CD" if cd_impact.is_cd(run) else "DM",
                z=np.array(zc) - (z.min() - 0.5 * h), r=np.array(rc), particles=int(sel.sum()))


def main(argv=None):
    ap = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    ap.add_argument("dirs", nargs="+", help="output directories of impact runs")
    ap.add_argument("-o", "--output", help="plot file (PNG); none: print only")
    ap.add_argument("--exp-length", type=float, help="experimental final length (mm)")
    ap.add_argument("--exp-footprint", type=float, help="experimental footprint diameter (mm)")
    ap.add_argument("--exp-lateral", type=float, nargs="*", default=[],
                    help="experimental radii (mm) at heights f L_f, as pairs f r (e.g. 0.5 4.40)")
    ap.add_argument("--title", default="Taylor test, OFHC Cu", help="plot title")
    args = ap.parse_args(argv)
    results = []
    for d in args.dirs:
        m = measure(d)
        results.append((d, m))
        line = (f"{d}: h {10 * m['h']:.4g} mm, {m['particles']} particles: "
                f"L {10 * m['length']:.3f} mm (L/L0 {m['length'] / m['L0']:.4f}), "
                f"D {10 * m['footprint']:.3f} mm (D/D0 {m['footprint'] / m['D0']:.4f})")
        if args.exp_length:
            line += f"; L vs experiment {100 * (10 * m['length'] / args.exp_length - 1):+.2f} %"
        if args.exp_footprint:
            line += f", D {100 * (10 * m['footprint'] / args.exp_footprint - 1):+.2f} %"
        print(line)
        if args.exp_lateral:  # the profile's radius at the same fractions of its own length
            f, r = np.array(args.exp_lateral[0::2]), np.array(args.exp_lateral[1::2])
            rr = 10 * np.interp(f * m["length"], m["z"], m["r"])
            print("  radius at f L_f: " + ", ".join(
                f"f {a:.3g}: {b:.3f} mm (experiment {c:.3f}, {b - c:+.3f})"
                for a, b, c in zip(f, rr, r)))
    if not args.output:
        return 0
    import matplotlib
    matplotlib.use("Agg")
    import matplotlib.pyplot as plt
    fig, ax = plt.subplots(figsize=(5.5, 7))
    m0 = results[0][1]
    R0, L0 = 5 * m0["D0"], 10 * m0["L0"]
    ax.plot([-R0, -R0, R0, R0], [0, L0, L0, 0], "k:", lw=1, label="initial rod")
    for d, m in results:
        zz, rr = 10 * m["z"], 10 * m["r"]
        lab = f"DM, h = {10 * m['h']:.3g} mm ({m['particles']} particles), c_s {m['cs']:g}"
        if m["model"] == "CD":
            lab = f"CD, layers {10 * m['h']:.3g} mm apart ({m['particles']} particles)"
        (ln,) = ax.plot(rr, zz, lw=1.5, label=lab)
        ax.plot(-rr, zz, lw=1.5, color=ln.get_color())
    if args.exp_length:
        ax.axhline(args.exp_length, color="r", lw=1, ls="--",
                   label=f"experiment: final length {args.exp_length:g} mm")
    if args.exp_footprint:
        ax.plot([-args.exp_footprint / 2, args.exp_footprint / 2], [0, 0], "r-", lw=4,
                label=f"experiment: footprint {args.exp_footprint:g} mm")
    if args.exp_lateral and args.exp_length:
        f, r = np.array(args.exp_lateral[0::2]), np.array(args.exp_lateral[1::2])
        ax.plot(np.concatenate([r, -r]), np.concatenate([f, f]) * args.exp_length, "rs", ms=4,
                label="experiment: radius at fractions of L_f")
    ax.set_xlabel("r (mm)")
    ax.set_ylabel("height above the wall (mm)")
    ax.set_aspect("equal")
    ax.legend(fontsize=7, loc="upper right")
    ax.set_title(args.title)
    fig.tight_layout()
    fig.savefig(args.output, dpi=130)
    print(f"wrote {args.output}")
    return 0


if __name__ == "__main__":
    sys.exit(main())
