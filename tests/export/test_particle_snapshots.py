# SPDX-License-Identifier: MIT
"""One snapshot name and one layout for every particle problem (docs/output.md, "Particle
snapshots"): each problem run briefly, its snapshots read with h5py, python/mscale and ASE.

    /usr/bin/python3 tests/export/test_particle_snapshots.py MSCALE SOURCE_DIR WORKDIR

For the coupled problem, cluster dynamics, the linear discrete model, the discrete model with
response: eos and the impact problem:
  - the run's HDF5 files besides the checkpoint and the grid's are exactly particles_NNNN.h5 (4 digits, one
    consecutive index), each with its sidecar particles_NNNN.xmf, and particles.xmf lists every
    sidecar in index order;
  - every snapshot has /particles/x [n][3] (cm), v [n][3] (km/s), mass [n] (g), material [n]
    (an integer index into the attribute material_names, naming the deck's materials), vertex
    (0..n-1), the attributes time (with time_units) and, where the problem finds fragments,
    fragment [n]; every float dataset has its units;
  - mscale.Run(dir).snapshots lists the same files in the same order, times increasing;
  - `mscale export --format extxyz` of the last snapshot read by ASE gives the positions and
    velocities of the HDF5 file, equal (17 significant digits round-trip every double), and the
    species of the material names.
And a run that goes unstable (tests/reliability/unstable/cd_piston_too_fast.yaml with
snapshots; an impact rod leaving its domain) writes particles_unstable.h5 in the same layout and
leaves particles.xmf listing the numbered snapshots (it used to rewrite it empty: the digit of
".h5" was taken for an index).
"""
import glob
import os
import re
import subprocess
import sys

import h5py
import numpy as np
from ase.io import read

mscale_bin, src, work = sys.argv[1:4]
sys.path.insert(0, os.path.join(src, "python"))
import mscale  # noqa: E402

# as the other run-based tests: Open MPI components loaded by dlopen keep memory past
# MPI_Finalize that LeakSanitizer cannot attribute (tests/lsan.supp), so no leak check here
RUN_ENV = dict(os.environ, ASAN_OPTIONS=os.environ.get("ASAN_OPTIONS", "") + ":detect_leaks=0")
os.makedirs(work, exist_ok=True)

DM_LINEAR = """problem: discrete_model
materials:
  - name: steel
    eos: {type: linear_elastic, rho0: 7.85, bulk_modulus: 66.666666666666667}
    shear_modulus: 100.0
  - name: al
    eos: {type: linear_elastic, rho0: 2.7, bulk_modulus: 70.0}
    shear_modulus: 26.0
discrete_model:
  spacing: 0.05
  domain: {lo: [0], hi: [1]}
  boundaries: {x_lo: wall, x_hi: free}
  layers: [{material: steel, x_max: 0.5}, {material: al}]
  initial: {profile: rod_sine, amplitude: 0.001, length: 1}
  steps: 4
  dt: 0.002
  output: {snapshot_times: [0, 0.004, 0.008]}
"""
with open(os.path.join(src, "tests/dm/data/impact_small_rod.yaml")) as f:
    IMPACT = f.read()  # the shared small rod (also test_paraview.py, test_taylor_profile.py)
# problem: (deck, its material names, first index, has fragments)
PROBLEMS = {
    "coupled": (os.path.join(src, "tests/coupling/data/cpl_restart.yaml"), None, 1, True),
    "cluster_dynamics": (os.path.join(src, "tests/cd/data/cd_restart_2d.yaml"), None, 0, False),
    "dm_linear": (DM_LINEAR, ["steel", "al"], 0, False),
    "dm_eos": (os.path.join(src, "tests/dm/data/dm_fin_piston_2d.yaml"), ["al6061"], 0, False),
    "impact": (IMPACT, ["cu"], 0, False),
}
# the HDF5 outputs that are not particle snapshots: checkpoints and the grid's files
OTHER_H5 = r"((cd|dm|coupled)_checkpoint|history|xt|profile_(\d+|final))"


def run(name, deck, expect=0):
    if not os.path.exists(deck):
        path = os.path.join(work, name + ".yaml")
        with open(path, "w") as f:
            f.write(deck)
        deck = path
    out = os.path.join(work, name)
    r = subprocess.run([mscale_bin, "run", deck, "-o", out, "--force", "--quiet"], env=RUN_ENV,
                       capture_output=True, text=True)
    assert r.returncode == expect, f"{name}: exit {r.returncode}\n{r.stderr}"
    return out


def text(v):
    return v.decode() if isinstance(v, bytes) else str(v)


def check_layout(path, names, fragments):
    """The shared layout of one snapshot; returns (n, time)."""
    with h5py.File(path, "r") as f:
        g = f["particles"]
        n = g["x"].shape[0]
        assert n > 0 and g["x"].shape == (n, 3), (path, g["x"].shape)
        for k, shape, unit in (("x", (n, 3), "cm"), ("v", (n, 3), "km/s"), ("mass", (n,), "g")):
            assert k in g and g[k].shape == shape and g[k].dtype.kind == "f", (path, k)
            assert text(g[k].attrs["units"]) == unit, (path, k, g[k].attrs.get("units"))
            assert np.all(np.isfinite(g[k][()])), (path, k)
        for k in ("material", "vertex") + (("fragment",) if fragments else ()):
            assert k in g and g[k].shape == (n,) and g[k].dtype.kind == "i", (path, k)
        assert np.array_equal(g["vertex"][()], np.arange(n)), path
        table = text(g.attrs["material_names"]).split(",")
        if names is not None:
            assert table == names, (path, table, names)
        mat = g["material"][()]
        assert mat.min() >= 0 and mat.max() < len(table), (path, mat.min(), mat.max(), table)
        for k, d in g.items():
            if d.dtype.kind == "f":
                assert "units" in d.attrs, f"{path}: {k} has no units"
        assert text(g.attrs["time_units"]) and np.isfinite(g.attrs["time"]), path
        return n, float(g.attrs["time"]), table, mat


for name, (deck, names, first, fragments) in PROBLEMS.items():
    out = run(name, deck)
    h5 = sorted(os.path.basename(p) for p in glob.glob(os.path.join(out, "*.h5")))
    snaps = [f for f in h5 if not re.fullmatch(OTHER_H5 + r"\.h5", f)]
    assert snaps and all(re.fullmatch(r"particles_\d{4}\.h5", f) for f in snaps), (name, h5)
    idx = [int(f[10:14]) for f in snaps]
    assert idx == list(range(first, first + len(snaps))), (name, snaps)
    xmf = open(os.path.join(out, "particles.xmf")).read()
    hrefs = re.findall(r'href="([^"]+)"', xmf)
    assert hrefs == [f[:-3] + ".xmf" for f in snaps], (name, hrefs, snaps)
    assert all(os.path.exists(os.path.join(out, h)) for h in hrefs), (name, hrefs)
    times = []
    for f in snaps:
        n, t, table, mat = check_layout(os.path.join(out, f), names, fragments)
        times.append(t)
    assert all(a < b for a, b in zip(times, times[1:])), (name, times)
    run_ = mscale.Run(out)
    assert [os.path.basename(s.path) for s in run_.snapshots] == snaps, name
    assert [s.time for s in run_.snapshots] == times, name
    last = os.path.join(out, snaps[-1])
    xyz = os.path.join(work, name + ".xyz")
    subprocess.run([mscale_bin, "export", last, "--format", "extxyz", "-o", xyz], env=RUN_ENV,
                   check=True)
    atoms = read(xyz, format="extxyz")
    with h5py.File(last, "r") as f:
        x, v = f["particles/x"][()], f["particles/v"][()]
    assert len(atoms) == len(x), name
    assert np.array_equal(atoms.positions, x), f"{name}: positions differ"
    velo = atoms.arrays["velo"] if "velo" in atoms.arrays else atoms.get_velocities()
    assert np.array_equal(velo, v), f"{name}: velocities differ"
    want = [mscale.snapshot.species_of(table[m]) for m in mat]
    assert atoms.get_chemical_symbols() == want, f"{name}: species"
    print(f"{name}: {len(snaps)} snapshots {snaps[0]}..{snaps[-1]}, {n} particles, materials "
          f"{table}: layout, series, Run.snapshots and ASE as expected")

def check_unstable(name, deck_text, names, series=True):
    """A run that goes unstable: exit 1, particles_unstable.h5 in the shared layout, and
    particles.xmf listing exactly the numbered snapshots written before (series), or no
    particles.xmf when there were none."""
    out = run(name, deck_text, 1)
    check_layout(os.path.join(out, "particles_unstable.h5"), names, False)
    numbered = sorted(os.path.basename(p)[:-3] + ".xmf"
                      for p in glob.glob(os.path.join(out, "particles_[0-9]*.h5")))
    assert bool(numbered) == series, f"{name}: numbered snapshots before the failure: {numbered}"
    if not series:
        assert not os.path.exists(os.path.join(out, "particles.xmf")), f"{name}: an empty series"
        print(f"{name}: particles_unstable.h5 in the shared layout; no series")
        return
    hrefs = re.findall(r'href="([^"]+)"', open(os.path.join(out, "particles.xmf")).read())
    assert hrefs == numbered, (f"{name}: particles.xmf after the unstable snapshot", hrefs, numbered)
    assert mscale.Run(out).unstable_snapshot is not None, name
    print(f"{name}: particles_unstable.h5 in the shared layout; particles.xmf lists "
          f"{len(hrefs)} numbered snapshots")


# cluster dynamics: a piston too fast (a snapshot every few steps, so the series holds some
# before the failure at step 10)
deck = open(os.path.join(src, "tests/reliability/unstable/cd_piston_too_fast.yaml")).read()
check_unstable("unstable_cd", deck + "  output: {snapshots: 1000}\n", ["al"])
# the coupled problem's particle region (cluster dynamics): the region's own snapshot
check_unstable("unstable_coupled",
               os.path.join(src, "tests/reliability/unstable/coupled_particles_too_fast.yaml"),
               ["pb"], series=False)
# impact: the rod flies away from the wall out of a short domain (its state, finite, is kept)
check_unstable("unstable_impact", IMPACT.replace("velocity: [0, 0, -0.3]", "velocity: [0, 0, 0.5]")
               .replace("t_end: 0.05", "t_end: 1.0").replace("hi: [1, 1, 1.5]", "hi: [1, 1, 1.0]"),
               ["cu"])
