# SPDX-License-Identifier: MIT
"""mscale export: an extended-XYZ export of a coupled snapshot read back by ASE (python3-ase)
and a LAMMPS text dump read back by parsing, both against the HDF5 snapshot read by h5py.

    /usr/bin/python3 tests/export/test_export.py MSCALE_BINARY SOURCE_DIR WORKDIR

Positions, velocities and fragment ids must be EQUAL (no tolerance): the exporter writes reals
with 17 significant digits, which round-trips every IEEE double exactly.
"""
import os
import subprocess
import sys

import h5py
import numpy as np
from ase.io import read

# as the other run-based tests: Open MPI components loaded by dlopen keep memory past
# MPI_Finalize that LeakSanitizer cannot attribute (tests/lsan.supp), so no leak check here
RUN_ENV = dict(os.environ, ASAN_OPTIONS=os.environ.get("ASAN_OPTIONS", "") + ":detect_leaks=0")
mscale, src, work = sys.argv[1:4]
run = os.path.join(work, "run")
subprocess.run(env=RUN_ENV, args=[mscale, "run", os.path.join(src, "tests/coupling/data/cpl_restart.yaml"), "-o",
                run, "--force", "--quiet"], check=True, stdout=subprocess.DEVNULL,
               stderr=subprocess.DEVNULL)
snap = sorted(f for f in os.listdir(run) if f.startswith("particles_") and f.endswith(".h5"))[-1]
snap = os.path.join(run, snap)
with h5py.File(snap, "r") as f:
    x, v = f["particles/x"][()], f["particles/v"][()]
    frag, gid = f["particles/fragment_id"][()], f["particles/gid"][()]
assert len(x) > 100, "the snapshot should hold the particle region"

xyz = os.path.join(work, "snap.xyz")
subprocess.run(env=RUN_ENV, args=[mscale, "export", snap, "--format", "extxyz", "-o", xyz], check=True)
atoms = read(xyz, format="extxyz")
assert len(atoms) == len(x)
assert np.array_equal(atoms.positions, x), "positions differ"
velo = atoms.arrays["velo"] if "velo" in atoms.arrays else atoms.get_velocities()
assert np.array_equal(velo, v), "velocities differ"
assert np.array_equal(atoms.arrays["fragment_id"], frag), "fragment ids differ"
assert np.array_equal(atoms.arrays["gid"], gid), "global ids differ"
assert not os.path.exists(xyz + ".part"), "the temporary file was left behind"

dump = os.path.join(work, "snap.dump")
subprocess.run(env=RUN_ENV, args=[mscale, "export", snap, snap, "--format", "lammps-dump", "-o", dump], check=True)
lines = open(dump).read().splitlines()
frames = [i for i, l in enumerate(lines) if l == "ITEM: TIMESTEP"]
assert len(frames) == 2, "two snapshots give two frames"
head = lines[frames[0] + 8].split()[2:]
rows = np.array([l.split() for l in lines[frames[0] + 9:frames[1]]], dtype=float)
col = {name: k for k, name in enumerate(head)}
assert np.array_equal(rows[:, col["x"]:col["x"] + 3], x)
assert np.array_equal(rows[:, [col["vx"], col["vy"], col["vz"]]], v)
assert np.array_equal(rows[:, col["id"]], gid + 1), "ids are gid + 1"

# bad input: a missing file and a bad format are usage/input errors (exit 2), nothing written
bad = subprocess.run(env=RUN_ENV, args=[mscale, "export", os.path.join(work, "none.h5"), "--format", "extxyz",
                      "-o", os.path.join(work, "bad.xyz")], capture_output=True, text=True)
assert bad.returncode == 2 and "none.h5" in bad.stderr, bad.stderr
assert not os.path.exists(os.path.join(work, "bad.xyz"))
bad = subprocess.run(env=RUN_ENV, args=[mscale, "export", snap, "--format", "pdb"], capture_output=True, text=True)
assert bad.returncode == 2 and "extxyz or lammps-dump" in bad.stderr, bad.stderr
print(f"export: {len(x)} particles round-trip exactly through extxyz (ASE) and lammps-dump")
