# SPDX-License-Identifier: MIT
"""Particle snapshots: the HDF5 files of every particle problem (``particles_NNNN.h5`` of the
coupled problem, cluster dynamics, the discrete model and the impact problem; docs/output.md,
"Particle snapshots"), read with h5py, and their extended-XYZ export.

A snapshot holds the group ``/particles``: ``x`` [n][3] (cm), ``v`` [n][3] (km/s), ``mass`` (g),
``material`` (an index into the attribute ``material_names``), ``vertex``, ``fragment`` where
the problem finds fragments, and the model's per-particle datasets, each float dataset with a
``units`` attribute (integer datasets such as ``gid``, ``material``, ``fragment`` and ``vertex``
carry none), and the group's attributes (``time``, ``time_units``, ``step``, ``r0``,
``period_y``, ``material_names``, ...).
"""
import io
import math
import os

import numpy as np

from .table import Table
from .units import INTERNAL_TIME, as_text

# Element symbols, so that ASE (which wants real species) reads the file (as app/cmd_export.c).
ELEMENTS = (
    "H He Li Be B C N O F Ne Na Mg Al Si P S Cl Ar K Ca Sc Ti V Cr Mn Fe Co Ni Cu Zn Ga Ge As Se"
    " Br Kr Rb Sr Y Zr Nb Mo Tc Ru Rh Pd Ag Cd In Sn Sb Te I Xe Cs Ba La Ce Pr Nd Pm Sm Eu Gd Tb"
    " Dy Ho Er Tm Yb Lu Hf Ta W Re Os Ir Pt Au Hg Tl Pb Bi Po At Rn Fr Ra Ac Th Pa U Np Pu Am Cm"
    " Bk Cf Es Fm Md No Lr").split()
_ELEMENT_SET = frozenset(ELEMENTS)


def species_of(material):
    """The element symbol a material name spells ("pb" -> "Pb"), else "X" (ASE's dummy)."""
    if not material or len(material) > 2:
        return "X"
    sym = material[0].upper() + material[1:].lower()
    return sym if sym in _ELEMENT_SET else "X"


class Snapshot:
    """One particle snapshot (HDF5), read lazily with h5py.

    ``snap["x"]`` is a per-particle dataset as a numpy array (read on first use, then kept),
    ``snap.units["x"]`` its unit, ``list(snap)`` the dataset names, ``len(snap)`` the number
    of particles, ``snap.time`` the snapshot time in ``snap.time_unit`` (NaN when the file has
    none), ``snap.attrs`` the attributes of ``/particles`` (and of the file's root),
    ``snap.material_names`` the material table (a list, or None when the file has none).
    ``snap.to_numpy()`` / ``snap.to_pandas()`` give every per-particle dataset as one
    structured array / DataFrame; ``snap.to_extxyz()`` the extended-XYZ frame that
    ``mscale export --format extxyz`` writes.

    Symmetry planes: a run with ``impact.symmetry`` writes the particles on the + side of its
    planes only (attributes ``symmetry_x`` etc., the planes' positions). Such a snapshot is
    unfolded here (``unfold=True``, the default): every dataset is given for the full body, the
    mirror images appended (a particle on a plane is its own image), positions ``x``, ``X0``
    mirrored, other [n][3] vectors (velocity) with the normal component negated, everything else
    copied; ``snap.folded`` is the number of particles in the file (``len(snap)`` the unfolded
    count). ``unfold=False`` reads the file as it is.
    """

    GROUP = "particles"

    def __init__(self, path, unfold=True):
        import h5py

        self.path = os.fspath(path)
        self._cache = {}
        with h5py.File(self.path, "r") as f:
            if self.GROUP not in f or "x" not in f[self.GROUP]:
                raise ValueError(f"{self.path}: not a particle snapshot (no /particles/x)")
            g = f[self.GROUP]
            root = {k: self._attr(v) for k, v in f.attrs.items()}
            self.attrs = dict(root)
            self.attrs.update({k: self._attr(v) for k, v in g.attrs.items()})
            self._shape, self._int, self._num, self.units = {}, {}, {}, {}
            for name in sorted(g):  # HDF5's name order, as app/cmd_export.c lists them
                d = g[name]
                if not hasattr(d, "shape"):
                    continue
                self._shape[name] = d.shape
                self._int[name] = d.dtype.kind in "iu"
                self._num[name] = d.dtype.kind in "iuf"
                u = as_text(d.attrs.get("units"))
                if u is not None:
                    self.units[name] = u
            if len(self._shape["x"]) != 2 or self._shape["x"][1] != 3:
                raise ValueError(f"{self.path}: /particles/x is {self._shape['x']}, not [n][3]")
            self.n = self._shape["x"][0]
        self.folded = self.n
        self.symmetry = [(a, float(self.attrs[f"symmetry_{c}"])) for a, c in enumerate("xyz")
                         if f"symmetry_{c}" in self.attrs]
        self._orbit = None
        if unfold and self.symmetry:
            self._unfold_map()
        t = root.get("time", self.attrs.get("time"))  # the root's time first, as the exporter
        self.time = float(t) if t is not None else math.nan
        self.time_unit = as_text(self.attrs.get("time_units")) or INTERNAL_TIME
        names = self.attrs.get("material_names")  # one string, "al,pb,air"
        if isinstance(names, (list, tuple, np.ndarray)):
            names = ",".join(as_text(n) for n in names)
        self.material_names = [s for s in names.split(",") if s] if names else None

    def _unfold_map(self):
        """The rows of the unfolded body: the file's particle of each (self._orbit) and which
        axes are mirrored (self._flip [n][3]); images across each plane of the particles off it."""
        import h5py

        with h5py.File(self.path, "r") as f:
            x = f[self.GROUP]["x"][()]
        tol = 1e-9 * float(self.attrs.get("r0", 1.0))
        idx, flip = np.arange(self.folded), np.zeros((self.folded, 3), bool)
        for a, pos in self.symmetry:
            off = np.abs(x[idx, a] - pos) > tol
            f2 = flip[off].copy()
            f2[:, a] = True
            idx, flip = np.concatenate([idx, idx[off]]), np.concatenate([flip, f2])
        self._orbit, self._flip, self.n = idx, flip, len(idx)
        for name, shp in self._shape.items():
            if len(shp) >= 1 and shp[0] == self.folded:
                self._shape[name] = (self.n,) + tuple(shp[1:])

    def _unfolded(self, name, raw):
        if self._orbit is None or raw.ndim == 0 or raw.shape[0] != self.folded:
            return raw
        out = raw[self._orbit].copy()
        if out.ndim == 2 and out.shape[1] == 3 and out.dtype.kind == "f":
            for a, pos in self.symmetry:
                m = self._flip[:, a]
                out[m, a] = 2 * pos - out[m, a] if name in ("x", "X0") else -out[m, a]
        return out

    @staticmethod
    def _attr(v):
        if isinstance(v, (bytes, np.bytes_)):
            return as_text(v)
        if isinstance(v, np.ndarray) and v.shape == ():
            v = v[()]
        if isinstance(v, np.generic):
            return v.item()
        return v

    @property
    def name(self):
        return os.path.splitext(os.path.basename(self.path))[0]

    def keys(self):
        """Every dataset of /particles (sorted by name, as HDF5 lists them)."""
        return tuple(self._shape)

    def __iter__(self):
        return iter(self._shape)

    def __contains__(self, name):
        return name in self._shape

    def __len__(self):
        return self.n

    def __getitem__(self, name):
        if name not in self._shape:
            raise KeyError(f"{self.path}: no dataset /particles/{name} "
                           f"(datasets: {', '.join(self._shape)})")
        if name not in self._cache:
            import h5py

            with h5py.File(self.path, "r") as f:
                self._cache[name] = self._unfolded(name, f[self.GROUP][name][()])
        return self._cache[name]

    def get(self, name, default=None):
        return self[name] if name in self else default

    def per_particle(self, export=False):
        """The numeric per-particle datasets other than x ([n] or [n][k]), in name order; with
        ``export=True`` only the [n], [n][1] and [n][3] ones, the fields ``mscale export``
        carries over (a stress tensor [n][9] is left out there)."""
        return [k for k, s in self._shape.items() if k != "x" and self._num[k] and len(s) in (1, 2)
                and s[0] == self.n and (len(s) == 1 or not export or s[1] in (1, 3))]

    def is_int(self, name):
        """True when the dataset is stored as an integer type."""
        return self._int[name]

    def to_table(self):
        """The per-particle datasets (x first) as a :class:`mscale.Table`."""
        cols = {"x": self["x"]}
        cols.update((k, self[k]) for k in self.per_particle())
        title = f"{self.name} at t = {self.time:.9g} ({self.time_unit})"
        return Table.from_columns(cols, self.units, title, self.path)

    def to_numpy(self):
        """Every per-particle dataset as one numpy structured array (vectors as [3] fields)."""
        return self.to_table().data

    def to_pandas(self):
        """A pandas DataFrame, one row per particle: vectors split into x, y, z (positions)
        and NAMEx, NAMEy, NAMEz (``v`` -> vx, vy, vz, as the LAMMPS dump names them), other
        [n][k] datasets into NAME_0 ... NAME_k-1; ``df.attrs["units"]`` holds the units,
        ``df.attrs["time"]`` the time."""
        import pandas as pd

        cols, units = {}, {}
        for k in ["x"] + self.per_particle():
            a = self[k]
            if a.ndim == 1 or a.shape[1] == 1:
                cols[k], units[k] = a.reshape(-1), self.units.get(k, "1")
                continue
            for c in range(a.shape[1]):
                key = ("xyz"[c] if k == "x" else k + "xyz"[c]) if a.shape[1] == 3 else f"{k}_{c}"
                cols[key], units[key] = a[:, c], self.units.get(k, "1")
        df = pd.DataFrame(cols)
        df.attrs.update(units=units, time=self.time, time_unit=self.time_unit, path=self.path)
        return df

    # -- export --------------------------------------------------------------------------
    def _species(self):
        names = self.material_names
        mat = "material" in self.per_particle(export=True) and \
            self._shape["material"][1:] in ((), (1,))
        if not mat or not names:
            sym = species_of(names[0]) if names and len(names) == 1 else "X"
            return [sym] * self.n
        syms = [species_of(s) for s in names]
        # (long) of the value, as the exporter: truncation toward zero
        idx = np.trunc(self["material"].reshape(-1).astype(np.float64)).astype(np.int64)
        return [syms[m] if 0 <= m < len(syms) else "X" for m in idx]

    def write_extxyz(self, f):
        """Write the extended-XYZ frame of this snapshot to the text stream ``f``: the format
        of ``mscale export --format extxyz`` (app/cmd_export.c), byte for byte. Raises
        ValueError on a non-finite value, as the exporter does."""
        fields = self.per_particle(export=True)
        data = []
        for k in fields:
            a = self[k]
            a = a.reshape(self.n, -1)
            if not self._int[k] and not np.all(np.isfinite(a)):
                raise ValueError(f"{self.path}: /particles/{k} is not finite")
            data.append((a, self._int[k]))
        x = self["x"]
        if not np.all(np.isfinite(x)):
            raise ValueError(f"{self.path}: /particles/x is not finite")
        head = [f"{self.n}\nProperties=species:S:1:pos:R:3"]
        for k, (a, is_int) in zip(fields, data):
            head.append(f":{'velo' if k == 'v' else k}:{'I' if is_int else 'R'}:{a.shape[1]}")
        tu = self.time_unit if len(self.time_unit) < 16 and not any(
            c in self.time_unit for c in '" \n') else INTERNAL_TIME
        head.append(f' pbc="F F F" units="pos:cm velo:km/s mass:g time:{tu}"')
        if math.isfinite(self.time):
            head.append(f" Time={self.time:.17g}")
        f.write("".join(head) + "\n")
        # each row: species, x y z, then every field's values; reals with 17 significant
        # digits (an exact round trip), integers as integers
        fmts = []
        for a, is_int in data:
            fmts.extend([" %.0f" if is_int else " %.17g"] * a.shape[1])
        row_fmt = "%s %.17g %.17g %.17g" + "".join(fmts) + "\n"
        cols = [a.astype(np.float64) for a, _ in data]
        table = np.hstack([x] + cols) if cols else x
        for s, row in zip(self._species(), table.tolist()):
            f.write(row_fmt % (s, *row))

    def to_extxyz(self, path=None):
        """The extended-XYZ text of this snapshot (as ``mscale export --format extxyz``
        writes it); written to ``path`` (via ``path.part``, then renamed) when given, else
        returned as a string. ASE reads it with ``ase.io.read(path, format="extxyz")``."""
        return write_extxyz([self], path)


def write_extxyz(snapshots, path=None):
    """Several snapshots as the frames of one extended-XYZ file (or string, without path)."""
    if path is None:
        buf = io.StringIO()
        for s in snapshots:
            s.write_extxyz(buf)
        return buf.getvalue()
    part = os.fspath(path) + ".part"
    try:
        with open(part, "w") as f:
            for s in snapshots:
                s.write_extxyz(f)
        os.replace(part, path)
    except BaseException:
        if os.path.exists(part):
            os.remove(part)
        raise
    return os.fspath(path)


def read_snapshot(path):
    """Open one particle snapshot (a :class:`Snapshot`)."""
    return Snapshot(path)
