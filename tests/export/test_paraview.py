# SPDX-License-Identifier: MIT
"""ParaView (Debian's python3-paraview, run by pvpython offscreen) opens a run's temporal XDMF
collections: a continuum run's profiles.xmf and the particles.xmf of every particle problem (the
coupled problem, cluster dynamics, the discrete model, linear and with response: eos, and the
impact problem), each a series of particles_NNNN.h5.

    pvpython --force-offscreen-rendering tests/export/test_paraview.py MSCALE SOURCE_DIR WORKDIR

Asserted against the HDF5 files themselves (h5py): the number of time steps, the points of each
step, one vertex cell per particle (so ParaView's default Surface view draws them), and the range
of one array. Exact comparisons: ParaView reads the same doubles.
"""
import glob
import os
import subprocess
import sys

import h5py
from paraview import servermanager
from paraview.simple import OpenDataFile

# as the other run-based tests: Open MPI components loaded by dlopen keep memory past
# MPI_Finalize that LeakSanitizer cannot attribute (tests/lsan.supp), so no leak check here
RUN_ENV = dict(os.environ, ASAN_OPTIONS=os.environ.get("ASAN_OPTIONS", "") + ":detect_leaks=0")
mscale, src, work = sys.argv[1:4]


def run(deck, out):
    subprocess.run(env=RUN_ENV, args=[mscale, "run", os.path.join(src, deck), "-o", out, "--force", "--quiet"],
                   check=True, stdout=subprocess.DEVNULL, stderr=subprocess.DEVNULL)
    return out


def check_series(xmf, h5files, coords, array, vertex_cells):
    reader = OpenDataFile(os.path.abspath(xmf))  # the Xdmf3 reader wants an absolute path
    times = list(reader.TimestepValues)
    assert len(times) == len(h5files), f"{xmf}: {len(times)} time steps, {len(h5files)} files"
    for t, h5 in zip(times, h5files):
        reader.UpdatePipeline(t)
        data = servermanager.Fetch(reader)
        with h5py.File(h5, "r") as f:
            npts = f[coords].shape[0]
            lo, hi = f[array[1]][()].min(), f[array[1]][()].max()
            group = f[coords.split("/")[0]]
            t_file = f.attrs["time"] if "time" in f.attrs else group.attrs["time"]
            assert t_file == t, (h5, t_file, t)
        assert data.GetNumberOfPoints() == npts, (h5, data.GetNumberOfPoints(), npts)
        if vertex_cells:
            assert data.GetNumberOfCells() == npts, f"{h5}: {data.GetNumberOfCells()} cells"
        else:
            assert data.GetNumberOfCells() == npts - 1, f"{h5}: segments between nodes"
        arr = data.GetPointData().GetArray(array[0]) or data.GetCellData().GetArray(array[0])
        assert arr is not None, f"{h5}: no array {array[0]}"
        assert arr.GetRange() == (lo, hi), (h5, arr.GetRange(), (lo, hi))
    return len(times)


cpl = run("tests/coupling/data/cpl_restart.yaml", os.path.join(work, "cpl"))
snaps = sorted(glob.glob(os.path.join(cpl, "particles_[0-9]*.h5")))
n1 = check_series(os.path.join(cpl, "particles.xmf"), snaps, "particles/x",
                  ("mass", "particles/mass"), True)
cont = run("inputs/continuum-sod.yaml", os.path.join(work, "sod"))
profiles = sorted(glob.glob(os.path.join(cont, "profile_[0-9]*.h5")))
n2 = check_series(os.path.join(cont, "profiles.xmf"), profiles, "nodes/xyz",
                  ("rho", "cells/rho"), False)
# every other particle problem: the same particles_NNNN.h5 series (docs/output.md, "Particle
# snapshots"): cluster dynamics, the discrete model (linear and response: eos) and impact
DM_LINEAR = """problem: discrete_model
materials:
  - name: steel
    eos: {type: linear_elastic, rho0: 7.85, bulk_modulus: 66.666666666666667}
    shear_modulus: 100.0
discrete_model:
  spacing: 0.05
  domain: {lo: [0], hi: [1]}
  boundaries: {x_lo: wall, x_hi: free}
  layers: [{material: steel}]
  initial: {profile: rod_sine, amplitude: 0.001, length: 1}
  steps: 4
  dt: 0.002
  output: {snapshot_times: [0, 0.004, 0.008]}
"""


def deck_file(name, text):
    os.makedirs(work, exist_ok=True)
    path = os.path.join(work, name + ".yaml")
    with open(path, "w") as f:
        f.write(text)
    return os.path.abspath(path)  # os.path.join(src, an absolute path) is that path


counts = {}
for name, deck, array in [
        ("cluster_dynamics", "tests/cd/data/cd_restart_2d.yaml", "pressure"),
        ("discrete_model", deck_file("dm_linear", DM_LINEAR), "von_mises"),
        ("discrete_model (eos)", "tests/dm/data/dm_fin_piston_2d.yaml", "von_mises"),
        ("impact", "tests/dm/data/impact_small_rod.yaml", "pressure")]:
    out = run(deck, os.path.join(work, name.replace(" ", "_").strip("()")))
    snaps = sorted(glob.glob(os.path.join(out, "particles_[0-9]*.h5")))
    assert len(snaps) >= 2, (name, snaps)
    counts[name] = check_series(os.path.join(out, "particles.xmf"), snaps, "particles/x",
                                (array, "particles/" + array), True)
print(f"paraview: coupled particles.xmf {n1} steps, profiles.xmf {n2} steps, " +
      ", ".join(f"{k} particles.xmf {v} steps" for k, v in counts.items()) +
      ", as in the HDF5 files")
