# SPDX-License-Identifier: MIT
"""A `cluster_dynamics` run seen as an `impact` run, so that tools/taylor_profile.py and
tools/piekutowski.py measure cluster dynamics with the same code as the discrete model
(docs/validation.md, "Taylor anvil test" and "Piekutowski perforation", cluster-dynamics rows).

``as_impact(run, spacing)`` returns ``run`` itself when it is not a cluster-dynamics run, else a
view with what the tools read from an impact run:

* ``deck``: an ``impact`` section made from the cluster_dynamics regions — body k is region k
  (a cylinder, sphere or box, with its centre, radius, length or size, velocity and material);
  ``spacing`` is h, the lattice's length scale the measures use: ``"layer"`` the spacing of the
  fcc (001) layers along an axis, a/2 = r0/√2 (so that the axial extent of n layers plus h is
  the rod's nominal length, as for the discrete model's cubic lattice), ``"volume"`` the edge of
  the volume per site, (r0³/√2)^(1/3) = 2^(-1/6) r0 (so that ρ0 h³ is a cluster's mass, the
  mass the perforation tool gives each particle);
* ``snapshots``: the particle snapshots with ``body`` (the particle's region, from its material:
  every region must have a material of its own), ``X0`` (its position in the first snapshot,
  the initial state after any relaxation, matched by gid), ``density`` (NaN: not defined per
  cluster) beside the snapshot's own x, v, mass, time;
* ``table("impact_history")``: cd_energy.csv as the impact history's columns: kinetic,
  internal = the pair potential energy, broken = the broken-bond energy, the discrete model's
  other terms 0, balance = total − total(0);
* ``cd_fragments(x)``: the fragment label of every particle, the connected components of the
  pairs closer than R_c in the current positions ([Davydov] §4.1: clusters closer than the
  interaction radius b·a belong to one particle).

Run with Debian's python (/usr/bin/python3: numpy, h5py, yaml).
"""
import numpy as np


def components(n, ii, kk):
    """Connected components of n particles joined by the pairs (ii[b], kk[b]): each particle's
    label is the smallest index in its component (min-label propagation with pointer jumping)."""
    label = np.arange(n)
    while True:
        lo = np.minimum(label[ii], label[kk])
        new = label.copy()
        np.minimum.at(new, ii, lo)
        np.minimum.at(new, kk, lo)
        new = new[new]
        if np.array_equal(new, label):
            return label
        label = new


def is_cd(run):
    return (run.deck or {}).get("problem") == "cluster_dynamics"


def as_impact(run, spacing="volume"):
    return CdAsImpact(run, spacing) if is_cd(run) else run


def _body(region):
    shape = region.get("shape", "box")
    v = [float(c) for c in region.get("velocity", [0, 0, 0])]
    b = dict(shape=shape, material=region["material"], velocity=v)
    if shape == "cylinder":
        axis = int(region.get("axis", 2))
        lo, hi = float(region["lo"][axis]), float(region["hi"][axis])
        c = [float(x) for x in region["center"]]
        c[axis] = 0.5 * (lo + hi)
        b.update(axis="xyz"[axis], radius=float(region["radius"]), length=hi - lo, center=c)
    elif shape == "sphere":
        b.update(radius=float(region["radius"]), center=[float(x) for x in region["center"]])
    elif shape == "box":
        lo, hi = np.array(region["lo"], float), np.array(region["hi"], float)
        b.update(center=list(0.5 * (lo + hi)), size=list(hi - lo))
    else:
        raise SystemExit(f"cluster_dynamics region of shape {shape}: not a body")
    return b


class _Snap:
    """A cluster-dynamics snapshot with the fields of an impact snapshot."""

    def __init__(self, snap, body, x0_by_gid):
        self._s = snap
        self.time, self.time_unit, self.n = snap.time, snap.time_unit, snap.n
        gid = np.asarray(snap["gid"]).astype(np.int64)
        self._extra = dict(body=body[gid], X0=x0_by_gid[gid], density=np.full(snap.n, np.nan))

    def __contains__(self, name):
        return name in self._extra or name in self._s

    def __getitem__(self, name):
        return self._extra[name] if name in self._extra else self._s[name]


class CdAsImpact:
    def __init__(self, run, spacing):
        self._run = run
        self.path = run.path
        cd = run.deck["cluster_dynamics"]
        r0 = float(cd["r0"])
        self.r0, self.rc = r0, float(cd.get("cutoff", 1.2)) * r0
        if spacing == "layer":
            h = r0 / np.sqrt(2.0)
        elif spacing == "volume":
            h = r0 * 2.0 ** (-1.0 / 6.0)
        else:
            raise ValueError(spacing)
        regions = cd["regions"]
        mats = [r["material"] for r in regions]
        if len(set(mats)) != len(mats):
            raise SystemExit(f"{run.path}: every region needs a material of its own "
                             "(the bodies are told apart by material)")
        self.deck = dict(run.deck)
        self.deck["impact"] = dict(spacing=h, horizon=self.rc / h,
                                   bodies=[_body(r) for r in regions])
        snaps = run.snapshots
        if not snaps:
            self.snapshots = []
            return
        names = snaps[0].material_names or mats
        body_of_mat = np.array([mats.index(nm) if nm in mats else -1 for nm in names])
        s0 = snaps[0]
        gid0 = np.asarray(s0["gid"]).astype(np.int64)
        ng = int(gid0.max()) + 1
        x0 = np.full((ng, 3), np.nan)
        x0[gid0] = np.asarray(s0["x"], float)
        body = np.full(ng, -1)
        body[gid0] = body_of_mat[np.asarray(s0["material"]).astype(int)]
        self.snapshots = [_Snap(s, body, x0) for s in snaps]

    def table(self, name):
        if name != "impact_history":
            return self._run.table(name)
        e = self._run.table("cd_energy")
        z = np.zeros(len(e["t"]))
        tot = np.asarray(e["total"], float)
        return dict(t=np.asarray(e["t"], float), kinetic=e["kinetic"], internal=e["potential"],
                    bond_penalty=z, broken=e["broken"], fracture_contact=z, wall_work=z,
                    wall_energy=z, balance=tot - tot[0], dissipated=e["dissipated"],
                    px=e["px"], py=e["py"], pz=e["pz"], p_x=e["px"], p_y=e["py"], p_z=e["pz"])

    def cd_fragments(self, x):
        """Labels of the components of the pairs closer than R_c (smallest index per label)."""
        x = np.asarray(x, float)
        n = len(x)
        rc = self.rc
        c = np.floor((x - x.min(axis=0)) / rc).astype(np.int64)
        M = int(c.max()) + 3
        key = ((c[:, 2] + 1) * M + (c[:, 1] + 1)) * M + (c[:, 0] + 1)
        order = np.argsort(key, kind="stable")
        skey = key[order]
        ukey, start, count = np.unique(skey, return_index=True, return_counts=True)
        ii, kk = [], []
        for dz in (-1, 0, 1):
            for dy in (-1, 0, 1):
                for dx in (-1, 0, 1):
                    nk = key + (dz * M + dy) * M + dx
                    pos = np.searchsorted(ukey, nk)
                    pos[pos >= len(ukey)] = 0
                    hit = ukey[pos] == nk
                    for s in range(int(count.max())):
                        ok = hit & (s < count[pos])
                        i = np.nonzero(ok)[0]
                        j = order[start[pos[ok]] + s]
                        keep = (j > i) & (np.sum((x[i] - x[j]) ** 2, axis=1) < rc * rc)
                        ii.append(i[keep]), kk.append(j[keep])
        return components(n, np.concatenate(ii), np.concatenate(kk))


def balance(outdir, snapshot=-1, e0=None):
    """Energy and momentum balance of a cluster-dynamics impact run at a snapshot (the final
    state by default), as fractions of E0 = the kinetic energy at t = 0 (or ``e0``, g (km/s)², for
    a run that starts at rest: the moving run's E0) and of |P0| (absolute when P0 = 0): kinetic
    (and its part in the bodies' bulk motion, Σ_b |P_b|²/2M_b over the regions; the rest is the
    clusters' motion relative to their body's centre of mass: heat, and the debris' spread),
    the potential energy's change since t = 0 (a relaxed polycrystal starts with some), broken,
    dissipated, the largest |total − total(0)| so far; the momentum change."""
    import mscale
    run = as_impact(mscale.Run(outdir))
    h = run.table("impact_history")
    snap = run.snapshots[snapshot]
    t = np.asarray(h["t"], float)
    k = int(np.argmin(np.abs(t - snap.time)))
    E0 = float(h["kinetic"][0]) if e0 is None else float(e0)
    if not E0 > 0.0:
        raise SystemExit(f"{outdir}: the run starts at rest (E0 = 0): give --e0, the energy "
                         "to measure it by (e.g. the moving run's E0)")
    P = np.stack([np.asarray(h[c], float) for c in ("px", "py", "pz")], axis=1)
    m, v, body = np.asarray(snap["mass"], float), np.asarray(snap["v"], float), snap["body"]
    kcm = 0.0
    for b in np.unique(body):
        s = body == b
        pb = (m[s, None] * v[s]).sum(axis=0)
        kcm += 0.5 * pb @ pb / m[s].sum()
    out = dict(t=float(t[k]), E0=E0, kinetic=float(h["kinetic"][k]) / E0, bulk=kcm / E0,
               potential=float(h["internal"][k] - h["internal"][0]) / E0,
               broken=float(h["broken"][k]) / E0,
               dissipated=float(h["dissipated"][k]) / E0,
               balance=float(np.max(np.abs(h["balance"][:k + 1]))) / E0,
               P0=P[0], P=P[k], dP=float(np.linalg.norm(P[k] - P[0]) / np.linalg.norm(P[0]))
               if np.linalg.norm(P[0]) > 0.0 else float(np.linalg.norm(P[k] - P[0])),
               mode=str(((run.deck or {}).get("cluster_dynamics") or {}).get("cutoff_mode", "")))
    return out


def main(argv=None):
    import argparse
    ap = argparse.ArgumentParser(description="energy and momentum balance of cluster-dynamics "
                                 "impact runs (fractions of E0 = K(0) and |P0|)")
    ap.add_argument("dirs", nargs="+")
    ap.add_argument("--snapshot", type=int, default=-1)
    ap.add_argument("--e0", type=float, default=None,
                    help="E0 in g (km/s)^2 instead of K(0) (for a run that starts at rest)")
    args = ap.parse_args(argv)
    for d in args.dirs:
        b = balance(d, args.snapshot, args.e0)
        dp = "|P - P0|/|P0|" if np.linalg.norm(b["P0"]) > 0.0 else "|P - P0| (g km/s)"
        print(f"{d} ({b['mode']} cutoff): t {b['t']:.3f} us, E0 {b['E0']:.5g} g(km/s)^2: "
              f"kinetic {b['kinetic']:.4f} "
              f"(each body's bulk motion {b['bulk']:.4f}, the rest: heat and the debris' spread "
              f"{b['kinetic'] - b['bulk']:.4f}), potential change {b['potential']:+.4f}, broken "
              f"{b['broken']:.4f}, dissipated {b['dissipated']:.4f}; "
              f"max |balance| {b['balance']:.2e}; P0 {np.array2string(b['P0'], precision=5)}, "
              f"P {np.array2string(b['P'], precision=5)}, {dp} {b['dP']:.3g}")
    return 0


if __name__ == "__main__":
    import os
    import sys
    sys.path.insert(0, os.path.join(os.path.dirname(os.path.abspath(__file__)), "..", "python"))
    sys.exit(main())
