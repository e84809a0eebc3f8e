# SPDX-License-Identifier: MIT
"""Snapshots and the failure report of the discrete model with response: eos (docs/input-dm.md,
docs/output.md), read back with h5py:

    python3 tests/dm/test_dm_fin_outputs.py MSCALE SOURCE_DIR WORKDIR

1. tests/dm/data/dm_fin_piston_2d.yaml (an elastic-plastic slab hit by a piston, 2D):
   - every float dataset of /particles carries its units; particles.xmf lists both snapshots
     (particles_NNNN.h5); particles/material indexes the table material_names ("al6061");
   - each snapshot agrees with the layer-averaged profile written at the same step (p, q, e,
     eps_p, sigma_u, J, rho, x, u_x: an independent path through the model's arrays), with
     x = X + w, rho J = rho0, the piston layers' velocity and the masses;
   - the energies summed over the last snapshot equal the energy history's last row (kinetic of
     the free particles, internal sum m e, bond penalty sum m e_hourglass);
   - the hourglass indicator equals a numpy least-squares fit of each family's displacements
     (the family and the fit built here from the particles' positions alone).
2. The same slab with a piston too fast for an inviscid step (courant 1, no viscosity): the run
   stops with exit 1 naming step, particle and quantity, writes particles_unstable.h5 of
   the last good step, and no output holds a NaN; that snapshot equals the snapshot of a run of
   the same deck stopped (steps: N) at that step, dataset by dataset, bit for bit.
"""
import glob
import os
import re
import subprocess
import sys

import h5py
import numpy as np

RUN_ENV = dict(os.environ, ASAN_OPTIONS=os.environ.get("ASAN_OPTIONS", "") + ":detect_leaks=0",
               OMP_NUM_THREADS="1")
mscale, src, work = sys.argv[1:4]
os.makedirs(work, exist_ok=True)
deck_text = open(os.path.join(src, "tests/dm/data/dm_fin_piston_2d.yaml")).read()
RHO0, H, NX, NY, UP = 2.703, 0.01, 60, 5, 0.3  # the deck's


def run(text, name, expect=0):
    deck = os.path.join(work, name + ".yaml")
    open(deck, "w").write(text)
    out = os.path.join(work, name)
    r = subprocess.run([mscale, "run", deck, "-o", out, "--force", "--quiet"], env=RUN_ENV,
                       capture_output=True, text=True)
    assert r.returncode == expect, (name, r.returncode, r.stderr)
    return out, r.stderr


def read_csv(path):
    return np.genfromtxt(path, delimiter=",", names=True, skip_header=2)


def close(a, b, rel, what):
    a, b = np.asarray(a, float), np.asarray(b, float)
    scale = max(np.abs(b).max(), 1e-300)
    err = np.abs(a - b).max() / scale
    assert err <= rel, f"{what}: max |a - b| / max |b| = {err:.3g} > {rel:.1g}"
    return err


UNITS = {"x": "cm", "v": "km/s", "mass": "g", "X": "cm", "w": "cm", "pressure": "GPa", "q": "GPa",
         "density": "g/cm^3", "energy": "kJ/g", "von_mises": "GPa", "eps_p": "1", "J": "1",
         "e_hourglass": "kJ/g", "hourglass": "1"}


def snapshot(path):
    with h5py.File(path, "r") as f:
        g = f["particles"]
        for k, u in UNITS.items():
            assert g[k].attrs["units"].decode() == u, (path, k, g[k].attrs["units"])
        d = {k: g[k][()] for k in g}
        d["attrs"] = dict(g.attrs)
    return d


def hourglass_numpy(X, w, period_y, delta):
    """sqrt(sum_k |dw_ik - C_i xi_ik|^2 / sum_k |xi_ik|^2), C_i the least-squares fit dw ~ C xi
    over the family |xi| < delta (periodic in y, free in x)."""
    n = len(X)
    out = np.zeros(n)
    for i in range(n):
        xi = X[:, :2] - X[i, :2]
        xi[:, 1] -= period_y * np.round(xi[:, 1] / period_y)
        r = np.hypot(xi[:, 0], xi[:, 1])
        fam = (r > 0) & (r < delta)
        dw = w[fam, :2] - w[i, :2]
        C, *_ = np.linalg.lstsq(xi[fam], dw, rcond=None)  # dw ~ xi C (C = (F - I)^T)
        z = dw - xi[fam] @ C
        out[i] = np.sqrt((z ** 2).sum() / (xi[fam] ** 2).sum())
    return out


# ---- 1. snapshots of a run that completes ----
out, _ = run(deck_text, "piston")
snaps = sorted(glob.glob(os.path.join(out, "particles_[0-9]*.h5")))
assert [os.path.basename(p) for p in snaps] == ["particles_0000.h5", "particles_0001.h5"], snaps
assert len(snaps) == 2, snaps
xmf = open(os.path.join(out, "particles.xmf")).read()
assert all(os.path.basename(s)[:-3] + ".xmf" in xmf for s in snaps), xmf
worst = 0.0
for k, path in enumerate(snaps):
    s = snapshot(path)
    prof = read_csv(os.path.join(out, f"dm_fin_profile_{k:03d}.csv"))
    t = float(re.search(r"t = ([0-9.e+-]+)", open(os.path.join(out, f"dm_fin_profile_{k:03d}.csv"))
                        .readline()).group(1))
    assert abs(s["attrs"]["time"] - t) <= 1e-9 * t, (path, s["attrs"]["time"], t)
    assert np.all(np.isfinite(np.concatenate([np.ravel(v) for kk, v in s.items() if kk != "attrs"])))
    # the profile: the mean over each x layer (particles in lattice order, x fastest); the CSV
    # holds 10 significant digits, so agreement to 1e-9 of the largest value
    lay = lambda a: np.asarray(a).reshape(NY, NX).mean(axis=0)  # noqa: E731
    for col, arr in [("p", s["pressure"]), ("q", s["q"]), ("e", s["energy"]), ("eps_p", s["eps_p"]),
                     ("sigma_u", s["von_mises"]), ("J", s["J"]), ("rho", s["density"]),
                     ("x", s["x"][:, 0]), ("u_x", s["v"][:, 0])]:
        worst = max(worst, close(lay(arr), prof[col], 1e-9, f"{path}: {col} vs the profile"))
    assert np.array_equal(s["x"], s["X"] + s["w"]), path
    names = s["attrs"]["material_names"]
    names = names.decode() if isinstance(names, bytes) else str(names)
    assert names == "al6061" and np.all(s["material"] == 0), (path, names)
    close(s["density"] * s["J"], RHO0, 1e-14, f"{path}: rho J = rho0")
    piston = (np.arange(NX * NY) % NX) < 2
    assert np.all(s["v"][piston, 0] == UP), path
    assert np.all(s["mass"] == RHO0 * H * H), path
    assert s["eps_p"].max() > 0 and s["von_mises"].max() > 0, f"{path}: no plastic flow"
    hg = hourglass_numpy(s["X"], s["w"], s["attrs"]["period_y"], 1.5 * H)
    # the same sums in another order (lstsq): round-off of the non-affine residual, which is
    # ~1e-2 of the bond length at the front and ~1e-18 where the flow is uniform
    close(s["hourglass"], hg, 1e-9, f"{path}: hourglass indicator vs numpy")
    assert s["hourglass"].max() > 1e-4, f"{path}: the front's non-affine motion is not seen"
energy = read_csv(os.path.join(out, "dm_fin_energy.csv"))[-1]
m = s["mass"]
free = ~piston
kin = 0.5 * (m[free] * (s["v"][free] ** 2).sum(axis=1)).sum()
# the CSV's 10 significant digits (5e-10 relative at worst) dominate the sums' round-off
close(kin, energy["kinetic"], 1e-9, "kinetic energy of the last snapshot")
close((m * s["energy"]).sum(), energy["internal"], 1e-9, "internal energy of the last snapshot")
close((m * s["e_hourglass"]).sum(), energy["bond_penalty"], 1e-9, "bond-penalty energy")
print(f"snapshots: {len(snaps)} steps, fields = profile layer means to {worst:.2g}, energies and "
      f"hourglass indicator as computed here")

# ---- 2. a run that fails ----
bad = deck_text.replace("velocity: 0.3", "velocity: 8.0").replace(
    "  piston:", "  viscosity: {quadratic: 0.0, linear: 0.0}\n  courant: 1.0\n  piston:").replace(
    "checkpoint_every: 60", "checkpoint_every: 0")
out, err = run(bad, "fails", expect=1)
m_ = re.search(r"step (\d+), t = \S+ us: particle (\d+) \(X = [^)]*\): (.+?) = (\S+); the run stops, "
               r"the last good state \(step (\d+), t = (\S+) us\) is in particles_unstable.h5",
               err)
assert m_, err
step, good = int(m_.group(1)), int(m_.group(5))
assert good == step - 1 and step > 1, err
s = snapshot(os.path.join(out, "particles_unstable.h5"))
assert s["attrs"]["step"] == good and abs(s["attrs"]["time"] - float(m_.group(6))) <= 1e-8, s["attrs"]
for f in glob.glob(os.path.join(out, "*.csv")) + glob.glob(os.path.join(out, "*.h5")):
    if f.endswith(".csv"):
        assert "nan" not in open(f).read().lower(), f"{f} holds a NaN"
    else:
        with h5py.File(f, "r") as h:
            for k, v in h["particles"].items():
                assert np.all(np.isfinite(v[()])), f"{f}: {k} not finite"
stopped = bad.replace("t_end: 0.06", f"steps: {good}").replace("snapshot_times: [0.03, 0.06]",
                                                                "snapshot_times: [1.0]")
out2, _ = run(stopped, "stopped")
ref = snapshot(os.path.join(out2, "particles_0000.h5"))
for k in UNITS:
    assert np.array_equal(s[k], ref[k]), f"unstable snapshot's {k} differs from the state at step {good}"
print(f"failure: step {step}, particle {m_.group(2)}, {m_.group(3)} = {m_.group(4)}; the snapshot "
      f"is the state of step {good}, bit for bit; no NaN in any output")
