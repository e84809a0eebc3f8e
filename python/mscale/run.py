# SPDX-License-Identifier: MIT
"""A run directory of ``mscale run DECK -o DIR`` as Python objects.

>>> run = Run("out/default")
>>> run.deck["problem"], run.run_info["status"]
('coupled', 'completed')
>>> p = run.profiles[-1]                 # the last grid profile (a Table)
>>> p["rho"], p.units["rho"], p.time     # numpy array, 'g/cm^3', 0.4 (in p.time_unit)
>>> run.histories["drive"]["u"]          # the drive node's velocity history, km/s
>>> run.snapshots[-1].to_extxyz("last.xyz")
"""
import glob
import os
import re

import numpy as np

from .snapshot import Snapshot
from .table import Table, read_csv
from .units import as_text


def _read_yaml(path):
    import yaml  # Debian: python3-yaml (setup.sh installs it)

    with open(path) as f:
        return yaml.safe_load(f)


def _newest_group(paths, prefix_re):
    """The paths whose prefix (the one group of prefix_re) is that of the most recently written
    file: a directory reused without a manifest may hold another model's files too (the
    discrete model writes dm_profile_NNN or dm_fin_profile_NNN by its response)."""
    groups = {}
    for p in paths:
        m = re.fullmatch(prefix_re, os.path.basename(p))
        if m:
            groups.setdefault(m.group(1), []).append(p)
    if not groups:
        return []
    return max(groups.values(), key=lambda g: max(os.path.getmtime(p) for p in g))


def _numbered(paths, stem_re):
    """Paths whose base name matches stem_re (one group: the number), sorted by number."""
    out = []
    for p in paths:
        m = re.fullmatch(stem_re, os.path.basename(p))
        if m:
            out.append((int(m.group(1)), p))
    return [p for _, p in sorted(out)]


class Arrays(dict):
    """Named numpy arrays of one HDF5 group (``run.xt``, the groups of a profile file), with
    ``.units`` (name -> unit, from each dataset's ``units`` attribute) and ``.attrs`` (the
    group's attributes)."""

    def __init__(self, arrays, units, attrs, path=None):
        super().__init__(arrays)
        self.units, self.attrs, self.path = dict(units), dict(attrs), path

    def label(self, name):
        """An axis label "name [unit]"."""
        return f"{name} [{self.units[name]}]" if name in self.units else name

    def __repr__(self):
        inner = ", ".join(f"{k} {tuple(v.shape)} [{self.units.get(k, '1')}]"
                          for k, v in self.items())
        return f"<mscale.Arrays {self.path}: {inner}>"


def read_h5_group(path, group="/"):
    """Every numeric dataset of one HDF5 group as an :class:`Arrays` (subgroups left out)."""
    import h5py

    with h5py.File(path, "r") as f:
        g = f[group]
        arrays, units = {}, {}
        for name in sorted(g):
            d = g[name]
            if hasattr(d, "shape"):
                arrays[name] = d[()]
                u = as_text(d.attrs.get("units"))
                if u is not None:
                    units[name] = u
        attrs = {k: (as_text(v) if isinstance(v, (bytes, np.bytes_)) else
                     (v.item() if isinstance(v, np.generic) else v)) for k, v in g.attrs.items()}
    return Arrays(arrays, units, attrs, path)


class Run:
    """One run directory of mscale (``mscale run DECK -o DIR``), read on demand.

    Attributes (each read on first use and then kept; None or empty when the run has none):

    ``deck``
        the resolved deck (``deck.resolved.yaml``: the deck with every default filled in), a
        dict.
    ``run_info``
        ``run_info.yaml`` (version, build, libraries, ranks, status, wall time), a dict.
    ``profiles``
        the profiles in time order, a list of :class:`mscale.Table`, each with ``.time``: the
        grid's ``profile_NNNN.csv``; else the discrete model's ``*profile_NNN.csv``; else
        cluster dynamics' ``cd_profiles.csv``, split at each output time.
    ``final_profile``
        ``profile_final.csv`` (the grid at the end of its run), a Table.
    ``histories``
        the grid's tagged-node histories, a dict tag -> Table (``history_TAG.csv``, else the
        groups of ``history.h5``; ``histories_from_h5()`` reads the latter at full
        precision); columns t, x, u and the states beside the node.
    ``energy``
        the particle models' energy balance (``cd_energy.csv``, ``*dm*energy.csv``), a Table.
    ``snapshots``
        the particle snapshots in order, a list of :class:`mscale.Snapshot`
        (``particles_NNNN.h5``, the one name of every particle problem's snapshots;
        ``unstable_snapshot`` is the last good state of a run that went unstable).
    ``fragments``
        ``fragments.csv`` (one row per fragment at the end of the particle phase), a Table.
    ``spectra``
        the fragment spectra N(g) at the snapshot times (``spectrum_NNNN.csv``), a list of
        Tables with ``.time``; ``spectrum`` (``spectrum.csv``, the end of the particle phase)
        and ``spectrum_detector`` (the arrivals at the detector) beside them.
    ``xt``
        the x–t data of the grid (``xt.h5``), an :class:`Arrays` (t, x, rho, p).

    ``run.table(NAME)`` reads any other CSV of the run (``run.table("arrivals")``),
    ``run.tables`` is a dict of every CSV by name, ``run.files`` the run's file names. When
    run_info.yaml lists the run's files (``manifest:``), only those are read.
    Tables are numpy structured arrays with units; ``.to_pandas()`` makes DataFrames (when
    python3-pandas is installed). Units are the run's own, as its files name them.
    """

    def __init__(self, path):
        self.path = os.fspath(path)
        if not os.path.isdir(self.path):
            raise FileNotFoundError(f"{self.path}: not a run directory")
        self._cache = {}

    def __repr__(self):
        return f"<mscale.Run {self.path}: {len(self.files)} files>"

    def _once(self, key, make):
        if key not in self._cache:
            self._cache[key] = make()
        return self._cache[key]

    def file(self, name):
        """The path of one file of the run (whether or not it exists)."""
        return os.path.join(self.path, name)

    def has(self, name):
        m = self.manifest
        return os.path.exists(self.file(name)) and (m is None or name in m)

    @property
    def manifest(self):
        """The set of file names run_info.yaml's ``manifest:`` lists (the files of the last run
        in the directory), or None for a run without one (killed, or an older mscale)."""
        def make():
            if not os.path.exists(self.file("run_info.yaml")):
                return None
            m = (_read_yaml(self.file("run_info.yaml")) or {}).get("manifest")
            return None if m is None else set(m) | {"run_info.yaml"}
        return self._once("manifest", make)

    @property
    def files(self):
        """The names of the run's files, sorted: those of the manifest when run_info.yaml has
        one (files of an earlier run or of someone else in the directory are left out), else
        every file in the directory."""
        m = self.manifest
        return sorted(f for f in os.listdir(self.path) if m is None or f in m)

    def _glob(self, pattern):
        m = self.manifest
        return sorted(p for p in glob.glob(os.path.join(glob.escape(self.path), pattern))
                      if m is None or os.path.basename(p) in m)

    # -- YAML ---------------------------------------------------------------------------
    @property
    def deck(self):
        return self._once("deck", lambda: _read_yaml(self.file("deck.resolved.yaml"))
                          if self.has("deck.resolved.yaml") else None)

    @property
    def run_info(self):
        return self._once("run_info", lambda: _read_yaml(self.file("run_info.yaml"))
                          if self.has("run_info.yaml") else None)

    @property
    def problem(self):
        """The deck's problem type ("continuum", "coupled", ...), or None."""
        return (self.deck or {}).get("problem")

    @property
    def log(self):
        """The text of run.log ("" when absent)."""
        if not self.has("run.log"):
            return ""
        with open(self.file("run.log")) as f:
            return f.read()

    # -- tables -------------------------------------------------------------------------
    def table(self, name):
        """One CSV of the run by name, with or without ".csv" (a Table); KeyError if absent."""
        base = name if name.endswith(".csv") else name + ".csv"
        if not self.has(base):
            raise KeyError(f"{self.path}: no {base}")
        return self._once(("csv", base), lambda: read_csv(self.file(base)))

    def _maybe(self, name):
        return self.table(name) if self.has(name + ".csv") else None

    @property
    def tables(self):
        """Every CSV of the run, a dict name (without .csv) -> Table."""
        return {os.path.basename(p)[:-4]: self.table(os.path.basename(p))
                for p in self._glob("*.csv")}

    @property
    def profiles(self):
        def make():
            grid = _numbered(self._glob("profile_*.csv"), r"profile_(\d+)\.csv")
            if grid:
                return [self.table(os.path.basename(p)) for p in grid]
            dm = _numbered(_newest_group(self._glob("*profile_*.csv"), r"(.*)profile_\d+\.csv"),
                           r".*profile_(\d+)\.csv")
            if dm:
                return [self.table(os.path.basename(p)) for p in dm]
            if self.has("cd_profiles.csv"):
                t = self.table("cd_profiles")
                out = []
                for tk in np.unique(t["t"]):
                    part = t.select(t["t"] == tk)
                    part.time, part.time_unit = float(tk), t.unit("t")
                    out.append(part)
                return out
            return []
        return self._once("profiles", make)

    @property
    def final_profile(self):
        return self._maybe("profile_final")

    @property
    def histories(self):
        def make():
            names = sorted(os.path.basename(p)[len("history_"):-4]
                           for p in self._glob("history_*.csv"))
            if not names:
                return self.histories_from_h5()
            return {name: self.table(f"history_{name}.csv") for name in names}
        return self._once("histories", make)

    def histories_from_h5(self):
        """The tagged-node histories of ``history.h5`` (full double precision; the CSVs carry
        10 significant digits), a dict tag -> Table with columns in name order; {} without
        the file."""
        if not self.has("history.h5"):
            return {}
        import h5py

        out = {}
        with h5py.File(self.file("history.h5"), "r") as f:
            for name in sorted(f):
                if hasattr(f[name], "items"):
                    out[name] = Table.from_h5_group(f[name], title=f"history of tagged node "
                                                    f"'{name}'", path=self.file("history.h5"))
        return out

    @property
    def energy(self):
        for p in _newest_group(self._glob("*energy.csv"), r"(.*)energy\.csv")[:1]:
            return self.table(os.path.basename(p))
        return None

    @property
    def fragments(self):
        return self._maybe("fragments")

    @property
    def spectra(self):
        return self._once("spectra", lambda: [
            self.table(os.path.basename(p))
            for p in _numbered(self._glob("spectrum_*.csv"), r"spectrum_(\d+)\.csv")])

    @property
    def spectrum(self):
        return self._maybe("spectrum")

    @property
    def spectrum_detector(self):
        return self._maybe("spectrum_detector")

    # -- HDF5 ---------------------------------------------------------------------------
    @property
    def unstable_snapshot(self):
        """The last good state of a run that went unstable (``particles_unstable.h5``), a
        :class:`mscale.Snapshot`, or None."""
        return self._once("unstable_snapshot", lambda: Snapshot(self.file("particles_unstable.h5"))
                          if self.has("particles_unstable.h5") else None)

    @property
    def snapshots(self):
        def make():
            paths = _numbered(self._glob("particles_*.h5"), r"particles_(\d+)\.h5")
            return [Snapshot(p) for p in paths]
        return self._once("snapshots", make)

    @property
    def xt(self):
        return self._once("xt", lambda: read_h5_group(self.file("xt.h5"))
                          if self.has("xt.h5") else None)

    def h5(self, name, group="/"):
        """The numeric datasets of one group of an HDF5 file of the run, an :class:`Arrays`
        (``run.h5("profile_final", "cells")``)."""
        base = name if name.endswith(".h5") else name + ".h5"
        return read_h5_group(self.file(base), group)
