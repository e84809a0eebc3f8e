#!/usr/bin/python3
# SPDX-License-Identifier: MIT
"""Hole, back-spray angle, debris-cloud leading edge and fragments of a sphere-on-plate `impact`
run (docs/validation.md, "Piekutowski perforation"; docs/input-impact.md), or of a
`cluster_dynamics` run whose regions 0 and 1 are the sphere and the plate (tools/cd_impact.py:
h = (r0³/√2)^(1/3), the edge of a cluster's volume; fragments: pairs closer than R_c).

  piekutowski.py OUTDIR... [--snapshot K] [-o plot.png] [--csv PREFIX]
                 [--exp-hole MM --exp-theta DEG]

Body 0 is the projectile (a sphere moving along +z), body 1 the plate (a box normal to z). From
the run's last particle snapshot (particles_NNNN.h5, the final state; or --snapshot K, an
index into them; read through python/mscale):

* hole in the recovered plate (compared with the experiment): the plate's remnant is the
  fragment of the plate (components of the bonds neither broken, both ends failed, nor torn,
  stretched beyond TEAR = 2 times their reference length) that holds its rim (the lattice sites
  within h of the box's edge: where a holder clamps the bumper; what is recovered, or what a
  radiograph shows edge-on). Seen along the axis, in 36 sectors, the hole's wall is at the
  innermost remnant particle (hole_outline); the diameter is the equal-area
  2 sqrt(mean r_in^2), the smallest and largest sector printed beside, and the same for the
  remnant's intact particles.
* areal-mass hole D_h (the earlier measure, printed beside): the plate particles still in the
  plate (|z − z_c| ≤ t, z_c the plate's centre, t its thickness) and slower than a tenth of
  the impact speed, failed or not, give the plate's areal mass in rings of width h about the
  impact axis; the hole's radius is where it first reaches half of the intact plate's ρ0 t.
  Beside it: 2 (min r − h/2) of the innermost particle still in the plate and the same for the
  unbroken particles only. [Piekutowski1993]'s measurement could not be read here
  (docs/validation.md).
* back-spray angle θ: the material thrown back out of the impact face (z < z_f − h, z_f the
  face the sphere struck). θ is measured from the plate's face (90° is straight back along the
  axis): θ_v = the mass-weighted median of atan2(−u_z, u_r) over the back-spray particles (the
  direction they fly); θ_e = the angle of the veil's tip seen from the areal-mass hole's rim,
  the median of atan2(z_f − z, r − r_h) over the 10 % of back-spray particles farthest from the
  rim; θ_r = a radiograph's silhouette, the straight line through the radius holding 95 % of
  the mass in each depth bin of h (veil_silhouette). All are printed, also from the axis.
* debris-cloud leading edge: the largest z of any particle, and its speed
  (z_max − z_f)/(t − t_c) with t_c = the time of first contact (the sphere's gap over its speed); the same for the front
  of the first 1 % of the total mass (a few fast grains aside), and the largest u_z.
* fragments: connected components of the bond graph: particles i, k of one body are bonded when
  their lattice sites are closer than the horizon δ (the families of dm_family.c, built once),
  and a bond is broken when both particles have failed (dm_fracture.c) or torn (above). The
  debris is every fragment but the remnant: its mass spectrum (cumulative number N(≥ m)) and
  mass-weighted axial velocity distribution are plotted (-o) and written (--csv PREFIX:
  PREFIX_fragments.csv, PREFIX_velocity.csv, units in their headers).
* energy as fractions of E0 at the snapshot's time, the balance's largest value so far, and
  the momentum's largest drift |P − P0|/|P0| (impact_history.csv).

Units: cm, km/s and 10 µs in the files; mm, km/s and µs in the printout and plot. Run with
Debian's python (/usr/bin/python3: numpy, matplotlib, yaml).
"""
import argparse
import os
import sys

import numpy as np

sys.path.insert(0, os.path.join(os.path.dirname(os.path.abspath(__file__)), "..", "python"))
import mscale  # noqa: E402  (python/mscale: the reader of mscale's outputs)
import cd_impact  # noqa: E402  (a cluster_dynamics run seen as an impact run)


def geometry(run):
    sec = run.deck["impact"]
    b0, b1 = sec["bodies"][0], sec["bodies"][1]
    if b0.get("shape") != "sphere" or b1.get("shape") != "box":
        raise SystemExit(f"{run.path}: bodies 0, 1 must be a sphere and a box (the plate)")
    h = float(sec["spacing"])
    delta = float(sec.get("horizon", 1.5)) * h
    c0, c1 = np.array(b0["center"], float), np.array(b1["center"], float)
    t = float(b1["size"][2])
    v = float(b0["velocity"][2])
    zf = c1[2] - 0.5 * t  # the face the sphere strikes
    gap = zf - (c0[2] + float(b0["radius"]))
    return dict(h=h, delta=delta, axis=c1[:2], zc=c1[2], t=t, zf=zf, v=v, t_contact=gap / v,
                D=2 * float(b0["radius"]), half=0.5 * np.array(b1["size"][:2], float))


TEAR = 2.0  # a bond longer than twice its reference length is torn (hole_remnant)
SECTORS = 36  # azimuthal sectors of the hole's outline (10 degrees each)


def hole_outline(dx, dy, wall=0.0, sectors=SECTORS):
    """The hole's outline seen along the axis through a set of particles (offsets dx, dy from
    the axis): per azimuthal sector the radius of its innermost particle, less `wall`. Returns
    the equal-area diameter 2 sqrt(mean r_in^2) (a ragged hole's diameter: the circle letting
    the same light through) and the smallest and largest 2 r_in; nan where a sector holds no
    particle. wall = 0: the hole's edge at the innermost particle's centre, which is the
    lattice's own (mass-equivalent) edge when a sector spans several spacings: a lattice
    punched at radius R gives 2R + 0.15 h (test_piekutowski_hole); taking the wall h/2 inside
    the particle, as for a straight lattice row, reads 0.85 h low there."""
    r = np.hypot(dx, dy)
    sec = np.minimum((np.arctan2(dy, dx) + np.pi) / (2 * np.pi) * sectors, sectors - 1)
    r_in = np.full(sectors, np.inf)
    np.minimum.at(r_in, sec.astype(int), r - wall)
    if not np.all(np.isfinite(r_in)):
        return np.nan, np.nan, np.nan
    r_in = np.maximum(r_in, 0.0)
    return 2 * np.sqrt(np.mean(r_in ** 2)), 2 * r_in.min(), 2 * r_in.max()


def plate_remnant(lab, X0, body, g):
    """The recovered plate: the fragment of the plate (body 1) that holds its outer rim (the
    lattice sites within h of the box's edge, where the experiment's holder clamps the bumper),
    by bonds that are neither broken (both ends failed, dm_fracture.c) nor torn (stretched
    beyond TEAR times their reference length: no bond of a solid survives a doubled length,
    whatever the model's correspondence stress still says about an intact particle whose
    neighbour has flown off): lab = fragments(..., x, TEAR). Returns the mask of its particles
    and the fraction of the rim's particles in it (1: the rim is one piece)."""
    d0 = np.abs(X0[:, :2] - g["axis"])
    rim = (body == 1) & np.any(d0 >= g["half"] - g["h"], axis=1)
    labs, counts = np.unique(lab[rim], return_counts=True)
    keep = labs[np.argmax(counts)]
    return (lab == keep) & (body == 1), counts.max() / counts.sum()


def hole_radius(r, m, h, areal0):
    """The radius where the plate's areal mass, in rings of width h about the axis, first
    reaches half its initial value areal0 = ρ0 t (linear between ring centres)."""
    edges = np.arange(0.0, r.max() + h, h)
    ring = np.histogram(r, bins=edges, weights=m)[0] / (np.pi * (edges[1:] ** 2 - edges[:-1] ** 2))
    cov = ring / areal0
    rc = 0.5 * (edges[1:] + edges[:-1])
    k = int(np.argmax(cov >= 0.5))
    if k == 0:
        return rc[0] if cov[0] >= 0.5 else np.nan
    return rc[k - 1] + (0.5 - cov[k - 1]) / (cov[k] - cov[k - 1]) * (rc[k] - rc[k - 1])


def fragments(X0, body, failed, h, delta, x=None, tear=None):
    """Fragment label of every particle: components of the unbroken bonds (|X0_i − X0_k| < δ,
    the same body, not both failed). With x and tear: a bond whose length |x_i − x_k| exceeds
    tear times its reference length |X0_i − X0_k| is torn too (see hole_remnant)."""
    n = len(body)
    ii, kk = [], []
    reach = int(np.ceil(delta / h))
    offs = [(a, b, c) for a in range(-reach, reach + 1) for b in range(-reach, reach + 1)
            for c in range(-reach, reach + 1)
            if 0 < (a * a + b * b + c * c) * h * h < delta * delta * (1 - 1e-9)]
    for bd in np.unique(body):
        idx = np.nonzero(body == bd)[0]
        lo = X0[idx].min(axis=0)
        g = np.rint((X0[idx] - lo) / h).astype(np.int64) + reach
        M = int(g.max()) + 2 * reach + 1
        key = (g[:, 2] * M + g[:, 1]) * M + g[:, 0]
        order = np.argsort(key)
        skey = key[order]
        for a, b, c in offs:
            if (a, b, c) < (0, 0, 0):
                continue  # each bond once
            nk = ((g[:, 2] + c) * M + (g[:, 1] + b)) * M + (g[:, 0] + a)
            pos = np.searchsorted(skey, nk)
            pos[pos >= len(skey)] = 0
            hit = skey[pos] == nk
            i, k = idx[hit], idx[order[pos[hit]]]
            ok = ~(failed[i] & failed[k])
            if tear is not None:
                ok &= (np.linalg.norm(x[i] - x[k], axis=1)
                       <= tear * np.linalg.norm(X0[i] - X0[k], axis=1))
            ii.append(i[ok]), kk.append(k[ok])
    return cd_impact.components(n, np.concatenate(ii), np.concatenate(kk))


def veil_silhouette(dz, r, m, h):
    """The back-spray angle as a radiograph shows it: the veil's outer edge. In depth bins of h
    behind the struck face (down to the depth above which 90 % of the back-spray's mass lies),
    the radius that 95 % of the bin's mass lies within (the silhouette's edge, a few stray
    grains aside); a straight line r = a + b dz fitted through them; the angle from the plate's
    face is atan(1/b) (90°: straight back)."""
    o = np.argsort(dz)
    zmax = dz[o][np.searchsorted(np.cumsum(m[o]), 0.9 * m.sum())]
    zs, rs = [], []
    for lo in np.arange(0.0, zmax, h):
        b = (dz >= lo) & (dz < lo + h)
        if b.sum() < 3:
            continue
        ob = np.argsort(r[b])
        cm = np.cumsum(m[b][ob])
        rs.append(r[b][ob][min(np.searchsorted(cm, 0.95 * cm[-1]), b.sum() - 1)])
        zs.append(lo + 0.5 * h)
    if len(zs) < 3:
        return np.nan
    slope = np.polyfit(zs, rs, 1)[0]
    return float(np.degrees(np.arctan2(1.0, slope)))


def measure(outdir, snapshot=-1):
    run = cd_impact.as_impact(mscale.Run(outdir), "volume")  # CD: ρ0 h³ = a cluster's mass
    g = geometry(run)
    if not run.snapshots:
        raise SystemExit(f"{run.path}: no particle snapshots (particles_NNNN.h5)")
    snap = run.snapshots[snapshot]
    body = np.asarray(snap["body"]).astype(int)
    x = np.asarray(snap["x"], float)
    X0 = np.asarray(snap["X0"], float)
    u = np.asarray(snap["v"], float)
    failed = np.asarray(snap["failed"]) > 0 if "failed" in snap else np.zeros(len(body), bool)
    rho = np.asarray(snap["density"], float)
    rho0 = {}
    for bd in (0, 1):
        mats = {m["name"]: m for m in run.deck["materials"]}
        rho0[bd] = float(mats[run.deck["impact"]["bodies"][bd]["material"]]["eos"]["rho0"])
    mass = np.array([rho0[b] for b in body]) * g["h"] ** 3  # g
    t_now = snap.time / (10.0 if snap.time_unit == "us" else 1.0)  # 10 µs, as the deck
    r = np.hypot(x[:, 0] - g["axis"][0], x[:, 1] - g["axis"][1])
    # hole
    speed = np.linalg.norm(u, axis=1)
    inplate = (body == 1) & (np.abs(x[:, 2] - g["zc"]) <= g["t"]) & (speed < 0.1 * g["v"])
    r_h = hole_radius(r[inplate], mass[inplate], g["h"], g["t"] * rho0[1])
    r_min = r[inplate].min() - 0.5 * g["h"]  # the innermost particle still in the plate
    r_h_unbroken = r[inplate & ~failed].min() - 0.5 * g["h"]  # the unbroken plate only
    # the hole in the recovered plate: the remnant that holds the plate's rim, seen along the
    # axis (all its particles, failed ones attached to it included; and its intact ones)
    lab = (run.cd_fragments(x) if hasattr(run, "cd_fragments")  # CD: pairs closer than R_c
           else fragments(X0, body, failed, g["h"], g["delta"], x=x, tear=TEAR))
    rem, rim_frac = plate_remnant(lab, X0, body, g)
    dxy = x[:, :2] - g["axis"]
    hole_rem = hole_outline(dxy[rem, 0], dxy[rem, 1])
    hole_rem_intact = hole_outline(dxy[rem & ~failed, 0], dxy[rem & ~failed, 1])
    # back-spray
    back = x[:, 2] < g["zf"] - g["h"]
    ur = np.where(r > 0, ((x[:, 0] - g["axis"][0]) * u[:, 0] + (x[:, 1] - g["axis"][1]) * u[:, 1])
                  / np.maximum(r, 1e-300), 0.0)
    theta_v = theta_e = theta_r = np.nan
    if back.sum() >= 5:
        ang = np.degrees(np.arctan2(-u[back, 2], ur[back]))
        o = np.argsort(ang)
        cm = np.cumsum(mass[back][o])
        theta_v = float(ang[o][np.searchsorted(cm, 0.5 * cm[-1])])
        dz, dr = g["zf"] - x[back, 2], r[back] - r_h
        far = np.hypot(dz, dr)
        sel = far >= np.quantile(far, 0.9)
        theta_e = float(np.median(np.degrees(np.arctan2(dz[sel], dr[sel]))))
        theta_r = veil_silhouette(g["zf"] - x[back, 2], r[back], mass[back], g["h"])
    # leading edge
    zmax = x[:, 2].max()
    oz = np.argsort(x[:, 2])[::-1]  # the front of the cloud's first 1 % of the mass
    z01 = x[oz, 2][np.searchsorted(np.cumsum(mass[oz]), 0.01 * mass.sum())]
    v_edge = (zmax - g["zf"]) / (t_now - g["t_contact"]) if np.isfinite(t_now) else np.nan
    v_edge01 = (z01 - g["zf"]) / (t_now - g["t_contact"]) if np.isfinite(t_now) else np.nan
    hist = run.table("impact_history")  # energies at the history row nearest to t (its t: µs)
    th = np.asarray(hist["t"], float)
    k = int(np.argmin(np.abs(th - 10 * t_now))) if np.isfinite(t_now) else len(th) - 1  # µs
    energy = {c: float(np.asarray(hist[c], float)[k]) for c in
              ("kinetic", "internal", "bond_penalty", "broken", "fracture_contact", "wall_work",
               "wall_energy", "balance")}
    energy["E0"] = float(np.asarray(hist["kinetic"], float)[0])
    P = np.stack([np.asarray(hist[c], float) for c in ("p_x", "p_y", "p_z")], axis=1)
    energy["dP"] = float(np.max(np.linalg.norm(P[:k + 1] - P[0], axis=1)) / np.linalg.norm(P[0]))
    energy["balance_max"] = float(np.max(np.abs(np.asarray(hist["balance"], float)[:k + 1])))
    # fragments (the same bonds as the remnant's): mass, particles, sphere's share, centroid
    # velocity and position; the remnant is the plate, not debris
    _, first, inv = np.unique(lab, return_index=True, return_inverse=True)
    fm = np.bincount(inv, weights=mass)
    frag = dict(mass=fm, n=np.bincount(inv),
                sphere=np.bincount(inv, weights=mass * (body == 0)) / fm, remnant=rem[first])
    for c, w in (("u_z", u[:, 2]), ("u_r", ur), ("z", x[:, 2] - g["zf"]), ("r", r)):
        frag[c] = np.bincount(inv, weights=mass * w) / fm
    frag["speed"] = np.hypot(frag["u_z"], frag["u_r"])
    fvz = frag["u_z"]
    return dict(g=g, t=t_now, hole_rem=hole_rem[0], hole_rem_min=hole_rem[1],
                hole_rem_max=hole_rem[2], hole_rem_intact=hole_rem_intact[0],
                rem_mass=mass[rem].sum(), rim_frac=rim_frac, hole=2 * r_h, hole_min=2 * r_min,
                hole_unbroken=2 * r_h_unbroken, theta_v=theta_v, theta_e=theta_e,
                theta_r=theta_r, zmax=zmax, v_edge=v_edge, v_edge01=v_edge01,
                uz_max=u[:, 2].max(), back_mass=mass[back].sum(), frag_mass=fm, frag_vz=fvz,
                frag=frag, rem=rem, x=x, body=body, failed=failed, n=len(body),
                nfailed=int(failed.sum()), rho=rho, energy=energy)


def _write_atomic(path, text):
    part = path + ".part"
    with open(part, "w") as f:
        f.write(text)
    os.replace(part, path)


VZ_BIN = 0.25  # km/s, the velocity distribution's bins


def write_csv(prefix, d, m):
    """PREFIX_fragments.csv (one row per fragment, the plate's remnant marked) and
    PREFIX_velocity.csv (the debris' mass per bin of axial velocity, the remnant left out)."""
    f = m["frag"]
    o = np.argsort(f["mass"])[::-1]
    head = (f"# fragments of {d} at t = {10 * m['t']:.4g} us (tools/piekutowski.py): components "
            f"of the unbroken bonds (not both failed, not stretched beyond {TEAR:g} times), mass "
            "descending; remnant = 1: the plate's remnant (the recovered plate); u_z, u_r: "
            "mass-mean axial and radial velocity of its particles; z: centroid beyond the struck "
            "face, r: mass-mean distance of its particles from the axis\n")
    rows = ["# units: mass [mg], particles [1], sphere_fraction [1], remnant [1], u_z [km/s], "
            "u_r [km/s], speed [km/s], z [mm], r [mm]",
            "mass,particles,sphere_fraction,remnant,u_z,u_r,speed,z,r"]
    rows += [f"{1e3 * f['mass'][k]:.6g},{f['n'][k]},{f['sphere'][k]:.4g},{int(f['remnant'][k])},"
             f"{f['u_z'][k]:.6g},{f['u_r'][k]:.6g},{f['speed'][k]:.6g},{10 * f['z'][k]:.6g},"
             f"{10 * f['r'][k]:.6g}" for k in o]
    _write_atomic(prefix + "_fragments.csv", head + "\n".join(rows) + "\n")
    deb = ~f["remnant"]
    lo = np.floor(f["u_z"][deb].min() / VZ_BIN) * VZ_BIN
    edges = np.arange(lo, f["u_z"][deb].max() + VZ_BIN, VZ_BIN)
    tot = np.histogram(f["u_z"][deb], edges, weights=f["mass"][deb])[0]
    sph = np.histogram(f["u_z"][deb], edges, weights=(f["mass"] * f["sphere"])[deb])[0]
    num = np.histogram(f["u_z"][deb], edges)[0]
    rows = [f"# debris velocity distribution of {d} at t = {10 * m['t']:.4g} us: fragments other "
            f"than the plate's remnant in bins of their axial velocity u_z ({VZ_BIN:g} km/s)",
            "# units: u_z_lo [km/s], u_z_hi [km/s], mass [mg], sphere_mass [mg], plate_mass [mg], "
            "fragments [1]", "u_z_lo,u_z_hi,mass,sphere_mass,plate_mass,fragments"]
    rows += [f"{edges[k]:.4g},{edges[k + 1]:.4g},{1e3 * tot[k]:.6g},{1e3 * sph[k]:.6g},"
             f"{1e3 * (tot[k] - sph[k]):.6g},{num[k]}" for k in range(len(tot))]
    _write_atomic(prefix + "_velocity.csv", "\n".join(rows) + "\n")
    print(f"wrote {prefix}_fragments.csv, {prefix}_velocity.csv")


def main(argv=None):
    ap = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    ap.add_argument("dirs", nargs="+", help="output directories of impact runs")
    ap.add_argument("--snapshot", type=int, default=-1,
                    help="index into the run's particle snapshots (-1: the final state)")
    ap.add_argument("-o", "--output", help="plot file (PNG); none: print only")
    ap.add_argument("--csv", metavar="PREFIX", help="write PREFIX_fragments.csv and "
                    "PREFIX_velocity.csv (the debris-cloud spectrum and velocity distribution) of "
                    "the last run")
    ap.add_argument("--exp-hole", type=float, default=17.3, help="experimental hole (mm)")
    ap.add_argument("--exp-theta", type=float, default=20.67, help="experimental θ (deg)")
    ap.add_argument("--title", default="Piekutowski perforation, Al on Al", help="plot title")
    args = ap.parse_args(argv)
    res = []
    for d in args.dirs:
        m = measure(d, args.snapshot)
        res.append((d, m))
        g = m["g"]
        big = np.sort(m["frag_mass"])[::-1]
        print(f"{d}: t {10 * m['t']:.3f} us, h {10 * g['h']:.4g} mm, {m['n']} particles "
              f"({m['nfailed']} failed): hole in the recovered plate {10 * m['hole_rem']:.3f} mm "
              f"({100 * (10 * m['hole_rem'] / args.exp_hole - 1):+.1f} % vs {args.exp_hole:g}; "
              f"sectors {10 * m['hole_rem_min']:.2f}-{10 * m['hole_rem_max']:.2f} mm, its intact "
              f"particles {10 * m['hole_rem_intact']:.3f} mm; remnant {m['rem_mass']:.3f} g, "
              f"rim in it {m['rim_frac']:.3f}); areal-mass hole {10 * m['hole']:.3f} mm "
              f"({100 * (10 * m['hole'] / args.exp_hole - 1):+.1f} %; "
              f"innermost particle {10 * m['hole_min']:.3f} mm, unbroken plate "
              f"{10 * m['hole_unbroken']:.3f} mm); "
              f"theta_v {m['theta_v']:.2f} deg ({m['theta_v'] - args.exp_theta:+.2f} vs "
              f"{args.exp_theta:g}), theta_e {m['theta_e']:.2f} deg, theta_r {m['theta_r']:.2f} "
              f"deg (from the face; from the axis {90 - m['theta_v']:.2f}, {90 - m['theta_e']:.2f}"
              f", {90 - m['theta_r']:.2f}); back-spray mass "
              f"{1e3 * m['back_mass']:.1f} mg; leading edge z {10 * (m['zmax'] - g['zf']):.2f} mm "
              f"beyond the face, {m['v_edge']:.3f} km/s (the front of 1 % of the mass "
              f"{m['v_edge01']:.3f} km/s, max u_z {m['uz_max']:.3f} km/s); "
              f"{len(big)} fragments, largest {1e3 * big[0]:.1f} mg"
              + (f", next {1e3 * big[1]:.2f} mg" if len(big) > 1 else ""))
        en = m["energy"]
        print("  energy / E0 = {:.4g} kJ: kinetic {:.4f}, internal {:.4f}, bond penalty {:.4f}, "
              "broken {:.4f}, fracture springs {:.2e}, contact stored {:.2e}, contact work {:.2e}, "
              "balance {:.1e} (max over the run so far {:.1e}), |P - P0|/|P0| <= {:.1e}".format(
                  en["E0"], *(en[c] / en["E0"] for c in ("kinetic", "internal", "bond_penalty",
                                                        "broken", "fracture_contact",
                                                        "wall_energy", "wall_work",
                                                        "balance", "balance_max")),
                  en["dP"]))
    if args.csv:
        write_csv(args.csv, *res[-1])
    if not args.output:
        return 0
    import matplotlib
    matplotlib.use("Agg")
    import matplotlib.pyplot as plt
    fig, axs = plt.subplots(1, 3, figsize=(14, 4.8))
    d, m = res[-1]
    g = m["g"]
    sl = np.abs(m["x"][:, 1] - g["axis"][1]) < 0.75 * g["h"]  # one or two lattice rows
    for s, c, lab in ((sl & m["rem"], "tab:blue", "plate: remnant"),
                      (sl & (m["body"] == 1) & ~m["rem"], "tab:cyan", "plate: debris"),
                      (sl & (m["body"] == 0), "tab:red", "sphere")):
        axs[0].scatter(10 * m["x"][s, 0], 10 * (m["x"][s, 2] - g["zf"]), s=2, c=c, label=lab)
    rh = 0.5 * args.exp_hole  # mm
    axs[0].plot([-rh, -rh], [0, 10 * g["t"]], "k-", lw=2)
    axs[0].plot([rh, rh], [0, 10 * g["t"]], "k-", lw=2,
                label=f"experiment: hole {args.exp_hole} mm")
    L = 25.0
    th = np.radians(args.exp_theta)
    for sgn in (-1, 1):
        axs[0].plot([sgn * rh, sgn * (rh + L * np.cos(th))], [0, -L * np.sin(th)], "k--", lw=1,
                    label=f"experiment: θ = {args.exp_theta}° from the face" if sgn > 0 else None)
        axs[0].plot([sgn * rh, sgn * (rh + L * np.sin(th))], [0, -L * np.cos(th)], "k:", lw=1,
                    label=f"or {args.exp_theta}° from the axis" if sgn > 0 else None)
    axs[0].set_xlabel("x (mm)")
    axs[0].set_ylabel("z − z_face (mm)")
    axs[0].set_aspect("equal")
    axs[0].plot([-5 * m["hole_rem"], 5 * m["hole_rem"]], [-0.5, -0.5], "g-", lw=3,
                label=f"DM hole (recovered plate) {10 * m['hole_rem']:.1f} mm")
    axs[0].legend(fontsize=7)
    axs[0].set_xlim(-30, 30)
    axs[0].set_title(f"slice |y| < 0.75 h at t = {10 * m['t']:.2f} µs")
    for d, m in res:
        deb = ~m["frag"]["remnant"]  # the debris: all fragments but the plate's remnant
        fm = np.sort(m["frag_mass"][deb])[::-1] * 1e3
        axs[1].loglog(fm, np.arange(1, len(fm) + 1), drawstyle="steps-post",
                      label=f"h = {10 * m['g']['h']:.3g} mm")
        edges = np.arange(np.floor(m["frag_vz"][deb].min() / VZ_BIN) * VZ_BIN,
                          m["frag_vz"][deb].max() + VZ_BIN, VZ_BIN)
        axs[2].hist(m["frag_vz"][deb], bins=edges, weights=m["frag_mass"][deb] * 1e3,
                    histtype="step", label=f"h = {10 * m['g']['h']:.3g} mm")
    axs[1].set_xlabel("fragment mass m (mg)")
    axs[1].set_ylabel("N(≥ m)")
    axs[1].legend(fontsize=7)
    axs[1].set_title("debris fragment spectrum (remnant left out)")
    axs[2].set_xlabel("fragment axial velocity u_z (km/s)")
    axs[2].set_ylabel(f"mass per {VZ_BIN:g} km/s (mg)")
    axs[2].legend(fontsize=7)
    axs[2].set_title("velocity distribution (mass-weighted)")
    fig.suptitle(args.title)
    fig.tight_layout()
    fig.savefig(args.output, dpi=120)
    print(f"wrote {args.output}")
    return 0


if __name__ == "__main__":
    sys.exit(main())
