# SPDX-License-Identifier: MIT
"""The Python package (python/mscale): Run(dir) on a continuum run and on a coupled run.

    /usr/bin/python3 tests/python/test_package.py MSCALE_BINARY SOURCE_DIR WORKDIR

Runs inputs/continuum-sod.yaml (400 cells, 0.3 s) and the short coupled deck of the restart
test (tests/coupling/data/cpl_restart.yaml: 194 particles, 1 s), then checks what
mscale.Run(dir) gives against independent readings of the same files: the CSVs parsed here with
the standard library's csv module, the HDF5 files read directly with h5py, the deck's own
numbers (cells, output times, tags, outputs), and `mscale export` for the extended XYZ. Shapes,
dtypes, units and values must agree; the tolerances are stated where a CSV (10 significant
digits) is compared with an HDF5 file (full double precision).
"""
import csv
import os
import subprocess
import sys

import h5py
import numpy as np

mscale_bin, src, work = sys.argv[1:4]
sys.path.insert(0, os.path.join(src, "python"))
import mscale  # noqa: E402

# as the other run-based tests: Open MPI components loaded by dlopen keep memory past
# MPI_Finalize that LeakSanitizer cannot attribute (tests/lsan.supp), so no leak check here
RUN_ENV = dict(os.environ, ASAN_OPTIONS=os.environ.get("ASAN_OPTIONS", "") + ":detect_leaks=0")
# A CSV holds %.10g (core/csv.c): 10 significant digits, a relative rounding error of at most
# 5e-10 of the value against the double in the HDF5 file; 1e-9 leaves a factor 2 for the value
# itself being near a power of ten. An absolute floor for values that are ~0 (velocities of
# still cells: 1e-300 never matters, a value printed as 0 is exactly 0).
CSV_RTOL, CSV_ATOL = 1e-9, 1e-300
checks = 0


def check(cond, what):
    global checks
    if not cond:
        raise AssertionError(what)
    checks += 1


def run(deck, name):
    out = os.path.join(work, name)
    res = subprocess.run([mscale_bin, "run", os.path.join(src, deck), "-o", out, "--force",
                          "--quiet"], env=RUN_ENV, capture_output=True, text=True)
    if res.returncode != 0:
        sys.exit(f"test_package: mscale run {deck} failed ({res.returncode}):\n{res.stderr}")
    return out


def csv_reference(path):
    """The CSV read with the standard library: names, units (split by hand), rows as floats."""
    with open(path) as f:
        lines = f.read().splitlines()
    units = {}
    for ln in lines:
        if ln.startswith("# units:"):
            for item in ln[len("# units:"):].split(", "):
                name, unit = item.strip().rsplit(" [", 1)
                units[name] = unit[:-1]
    rows = list(csv.reader(ln for ln in lines if not ln.startswith("#")))
    names, body = rows[0], rows[1:]
    cols = {n: np.array([float(r[k]) for r in body]) for k, n in enumerate(names)}
    return names, units, cols


def same_as_csv(table, path):
    """Every column of a Table equals the CSV (same decimal text parsed to the same double:
    both parsers round correctly), with the units of the file's units line."""
    names, units, cols = csv_reference(path)
    check(list(table.names) == names, f"{path}: columns {table.names} != {names}")
    check(table.units == units, f"{path}: units {table.units} != {units}")
    check(len(table) == len(cols[names[0]]), f"{path}: {len(table)} rows")
    for n in names:
        check(np.array_equal(table[n].astype(float), cols[n]), f"{path}: column {n} differs")


def close(a, b, what):
    check(a.shape == b.shape, f"{what}: shape {a.shape} != {b.shape}")
    check(np.allclose(a, b, rtol=CSV_RTOL, atol=CSV_ATOL), f"{what}: CSV and HDF5 differ by "
          f"{np.max(np.abs(a - b) / np.maximum(np.abs(b), 1e-300)):.3g} (relative)")


def h5_units(dataset):
    u = dataset.attrs["units"]
    return u.decode() if isinstance(u, bytes) else str(u)


# ---------------------------------------------------------------------------------------------
# 1. A continuum run: the Sod tube
sod = run("inputs/continuum-sod.yaml", "sod")
r = mscale.Run(sod)
cont = r.deck["continuum"]
ncell = sum(layer["cells"] for layer in cont["layers"])
times = cont["output"]["times"]
check(r.problem == "continuum", f"problem {r.problem}")
check(r.run_info["status"] == "completed", f"status {r.run_info['status']}")
check(len(r.profiles) == len(times), f"{len(r.profiles)} profiles for output times {times}")
for k, (p, t) in enumerate(zip(r.profiles, times)):
    path = os.path.join(sod, f"profile_{k:04d}.csv")
    check(p.path == path, f"profile {k} is {p.path}")
    check(len(p) == ncell, f"{path}: {len(p)} rows for {ncell} cells")
    # the title prints the time with %g (6 significant digits): relative 5e-6 at most; the
    # deck's times are internal (10 us), the title's in the unit it names (us)
    t_us, pt_us = mscale.to_us(t, "10us"), mscale.to_us(p.time, p.time_unit)
    check(p.time_unit == "us", f"{path}: time unit {p.time_unit}")
    check(abs(pt_us - t_us) <= 5e-6 * abs(t_us), f"{path}: time {p.time} {p.time_unit} != {t}")
    check(p["cell"].dtype == np.int64 and np.array_equal(p["cell"], np.arange(ncell)),
          f"{path}: the cell column is not the int64 index 0..n-1")
    check(p["rho"].dtype == np.float64, f"{path}: rho is {p['rho'].dtype}")
    same_as_csv(p, path)
    with h5py.File(os.path.join(sod, f"profile_{k:04d}.h5"), "r") as h:
        for n in ("x", "rho", "e", "p", "c"):
            close(p[n], h["cells"][n][()], f"{path}: {n}")
            check(p.units[n] == h5_units(h["cells"][n]), f"{path}: unit of {n} differs from HDF5")
        # planar geometry: a cell's mass is per unit area; the step a count (docs/output.md)
        check(h5_units(h["cells"]["mass"]) == "g/cm^2", f"{path}: cells/mass unit")
        check(np.issubdtype(h.attrs["step"].dtype, np.integer), f"{path}: step not an integer")
        tu = h.attrs["time_units"]
        check(p.time_unit == (tu.decode() if isinstance(tu, bytes) else tu), f"{path}: time unit")
same_as_csv(r.final_profile, os.path.join(sod, "profile_final.csv"))
tags = [t["name"] for t in cont["tags"]]
check(sorted(r.histories) == sorted(tags), f"histories {list(r.histories)} for tags {tags}")
exact = r.histories_from_h5()
for tag in tags:
    hist, path = r.histories[tag], os.path.join(sod, f"history_{tag}.csv")
    same_as_csv(hist, path)
    with h5py.File(os.path.join(sod, "history.h5"), "r") as h:
        g = h[tag]
        for n in hist.names:
            close(hist[n], g[n][()], f"{path}: {n}")
            check(hist.units[n] == h5_units(g[n]), f"{path}: unit of {n} differs from HDF5")
            check(np.array_equal(exact[tag][n], g[n][()]), f"history.h5 {tag}/{n} not exact")
        check(np.issubdtype(g.attrs["node"].dtype, np.integer), f"history.h5 {tag}: node")
        check(h5_units(g["t"]) == "us", f"history.h5 {tag}/t: unit {h5_units(g['t'])}")
xt = r.xt
nf = len(xt["t"])
check(nf >= 2 and xt["x"].shape == (nf, ncell + 1), f"xt x {xt['x'].shape}, {nf} frames")
for q in ("rho", "p"):
    check(xt[q].shape == (nf, ncell), f"xt {q} {xt[q].shape}")
with h5py.File(os.path.join(sod, "xt.h5"), "r") as h:
    for n in ("t", "x", "rho", "p"):
        check(np.array_equal(xt[n], h[n][()]) and xt.units[n] == h5_units(h[n]), f"xt {n}")
# the last x-t frame is the final profile: the same state (to the CSV's digits)
close(r.final_profile["rho"], xt["rho"][-1], "xt rho[-1] vs profile_final")
check(r.snapshots == [] and r.fragments is None and r.spectra == [], "a continuum run: no "
      "particles, fragments or spectra")
if mscale.HAVE_PANDAS:  # python3-pandas (setup.sh installs it; the package runs without it)
    df = r.final_profile.to_pandas()
    check(df.shape == (ncell, len(r.final_profile.names)), f"DataFrame shape {df.shape}")
    check(df.attrs["units"]["p"] == r.final_profile.units["p"], "DataFrame units")
    check(np.array_equal(df["rho"].to_numpy(), r.final_profile["rho"]), "DataFrame values")
else:
    print("test_package: python3-pandas absent, the DataFrame checks are skipped")

# ---------------------------------------------------------------------------------------------
# 2. A coupled run (grid, drive, cluster-dynamics region, fragments, transport)
cpl = run("tests/coupling/data/cpl_restart.yaml", "coupled")
r = mscale.Run(cpl)
deck = r.deck["coupled"]
check(r.problem == "coupled" and r.run_info["status"] == "completed", "coupled run completed")
check(sorted(r.histories) == sorted(t["name"] for t in deck["grid"]["tags"]), "coupled tags")
check(deck["drive"]["tag"] in r.histories, "the drive node's history")
snaps = r.snapshots
check(len(snaps) == deck["time"]["outputs"], f"{len(snaps)} snapshots, deck outputs "
      f"{deck['time']['outputs']}")
for s in snaps:
    with h5py.File(s.path, "r") as h:
        g = h["particles"]
        check(len(s) == g["x"].shape[0] and s["x"].shape == (len(s), 3), f"{s.path}: shape")
        check(s.time == g.attrs["time"], f"{s.path}: time")
        for n in g:
            check(np.array_equal(s[n], g[n][()]), f"{s.path}: {n} differs")
            if "units" in g[n].attrs:
                check(s.units[n] == h5_units(g[n]), f"{s.path}: unit of {n}")
    check(s.units["x"] == "cm" and s.units["v"] == "km/s" and s.units["mass"] == "g",
          f"{s.path}: units {s.units}")  # the snapshot writer's units (docs/output.md)
    arr = s.to_numpy()
    check(arr["x"].shape == (len(s), 3) and np.array_equal(arr["v"], s["v"]), "to_numpy")
    if mscale.HAVE_PANDAS:
        df = s.to_pandas()
        check(np.array_equal(df[["x", "y", "z"]].to_numpy(), s["x"]), "to_pandas positions")
        check(np.array_equal(df["vx"].to_numpy(), s["v"][:, 0]), "to_pandas velocities")
# extended XYZ: byte for byte what `mscale export` writes, and ASE reads it back exactly
last = snaps[-1]
ref = subprocess.run([mscale_bin, "export", last.path, "--format", "extxyz"], env=RUN_ENV,
                     check=True, capture_output=True, text=True).stdout
check(last.to_extxyz() == ref, "to_extxyz differs from mscale export")
xyz = last.to_extxyz(os.path.join(work, "last.xyz"))
check(not os.path.exists(xyz + ".part"), "the temporary file was left behind")
both = mscale.write_extxyz(snaps, None)
ref2 = subprocess.run([mscale_bin, "export"] + [s.path for s in snaps] + ["--format", "extxyz"],
                      env=RUN_ENV, check=True, capture_output=True, text=True).stdout
check(both == ref2, "several frames differ from mscale export")
# the run's snapshots name their one material (docs/output.md, "Units")
names = [m["name"] for m in r.deck["materials"]]
check(last.material_names is not None and len(last.material_names) == 1
      and last.material_names[0] in names and np.all(last["material"] == 0),
      f"material table of {last.path}: {last.material_names}")
# species from a material table: a copy of the snapshot given a material per particle (0, 1,
# and 2, which the table does not name) and the names "pb,air" (Pb, then X: not an element)
named = os.path.join(work, "named.h5")
with h5py.File(last.path, "r") as src_h, h5py.File(named, "w") as h:
    src_h.copy("particles", h)
    if "material" in h["particles"]:  # the run's own table (one material): replaced here
        del h["particles"]["material"]
    h["particles"].create_dataset("material", data=np.arange(len(last)) % 3)
    h["particles"].attrs["material_names"] = np.bytes_("pb,air")
ref = subprocess.run([mscale_bin, "export", named, "--format", "extxyz"], env=RUN_ENV,
                     check=True, capture_output=True, text=True).stdout
named_snap = mscale.read_snapshot(named)
check(named_snap.material_names == ["pb", "air"], f"material names {named_snap.material_names}")
check(named_snap.to_extxyz() == ref, "to_extxyz with a material table differs from mscale export")
check([ln.split()[0] for ln in ref.splitlines()[2:5]] == ["Pb", "X", "X"], "species column")
try:
    from ase.io import read  # Debian's python3-ase (setup.sh)

    atoms = read(xyz, format="extxyz")
    check(np.array_equal(atoms.positions, last["x"]), "ASE positions")
    check(np.array_equal(atoms.arrays["fragment_id"], last["fragment_id"]), "ASE fragment ids")
except ImportError:
    print("test_package: python3-ase absent, the ASE read-back is skipped")
# fragments and spectra at the end of the particle phase, against the last snapshot
frag = r.fragments
same_as_csv(frag, os.path.join(cpl, "fragments.csv"))
check(frag["id"].dtype == np.int64 and frag["count"].dtype == np.int64, "integer ids, counts")
fid = last["fragment"]
ids, counts = np.unique(fid[fid >= 0], return_counts=True)
check(np.array_equal(ids, frag["id"]) and np.array_equal(counts, frag["count"]),
      "fragments.csv ids and cluster counts vs the last snapshot")
mass = np.bincount(fid[fid >= 0], weights=last["mass"][fid >= 0])
close(frag["mass"], mass, "fragment masses vs the last snapshot")
check(frag.units["mass"] == "g" and frag.units["vx"] == "km/s", f"fragment units {frag.units}")
check(len(r.spectra) == len(snaps), f"{len(r.spectra)} spectra for {len(snaps)} snapshots")
for sp, s in zip(r.spectra, snaps):
    same_as_csv(sp, sp.path)
    check(abs(sp.time - s.time) <= 5e-6 * abs(s.time), f"{sp.path}: time {sp.time} vs {s.time}")
    check(sp.time_unit == s.time_unit, f"{sp.path}: time unit {sp.time_unit} vs {s.time_unit}")
sp = r.spectrum
check(sp["count"].sum() == len(frag) and (sp["g"] * sp["count"]).sum() == frag["count"].sum(),
      "spectrum.csv counts the fragments of fragments.csv")
check(r.spectrum_detector is not None and r.spectrum_detector.names == ("g", "count", "mass"),
      "spectrum_detector.csv (may be empty, with its columns)")
# every CSV of both runs reads, and every column has a unit
for d in (sod, cpl):
    for name, t in mscale.Run(d).tables.items():
        check(set(t.units) == set(t.names), f"{name}: columns without units")

# ---------------------------------------------------------------------------------------------
# 3. The tools read through the package: plot_run.py on both runs
for d in (sod, cpl):
    subprocess.run(["/usr/bin/python3", os.path.join(src, "tools/plot_run.py"), d], check=True,
                   stdout=subprocess.DEVNULL)
    check(os.path.exists(os.path.join(d, "plots", "histories.png")), f"{d}: plots")
check(os.path.exists(os.path.join(cpl, "plots", "drive.png")), "coupled plots")

# python3 -m mscale RUNDIR: a summary naming every table with its rows
res = subprocess.run(["/usr/bin/python3", "-m", "mscale", cpl], capture_output=True, text=True,
                     env=dict(os.environ, PYTHONPATH=os.path.join(src, "python")))
check(res.returncode == 0 and f"fragments: {len(frag)} rows" in res.stdout, res.stdout + res.stderr)

# 4. Errors name the file
for bad, exc in ((os.path.join(work, "none"), FileNotFoundError),):
    try:
        mscale.Run(bad)
        check(False, "Run of a missing directory")
    except exc as e:
        check(bad in str(e), f"the error names the directory: {e}")
empty = os.path.join(work, "empty.csv")
with open(empty, "w") as f:
    f.write("# only a title\n")
try:
    mscale.read_csv(empty)
    check(False, "a CSV without a header")
except ValueError as e:
    check(empty in str(e), f"the error names the file: {e}")
try:
    r.fragments["nope"]
    check(False, "an unknown column")
except KeyError as e:
    check("nope" in str(e) and "mass" in str(e), f"the error lists the columns: {e}")
print(f"test_package: {checks} checks passed (continuum: {ncell} cells, {len(times)} profiles; "
      f"coupled: {len(snaps)} snapshots of {len(last)} particles, {len(frag)} fragments)")
