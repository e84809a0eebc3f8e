# SPDX-License-Identifier: MIT
"""mscale's outputs in Python: a run directory as numpy arrays (or pandas DataFrames) with units.

Use it from the repository (or an install's ``share/mscale/python``) with Debian's python::

    PYTHONPATH=python /usr/bin/python3
    >>> import mscale
    >>> run = mscale.Run("out/default")
    >>> run.deck["problem"]                      # deck.resolved.yaml, a dict
    >>> p = run.profiles[-1]                     # a Table: p["rho"], p.units["rho"], p.time
    >>> run.histories["drive"].to_pandas()       # a DataFrame, units in df.attrs["units"]
    >>> s = run.snapshots[-1]                    # a Snapshot: s["x"] [n][3] cm, s["v"] km/s
    >>> s.to_extxyz("last.xyz")                  # what `mscale export --format extxyz` writes

What is here (docs/output.md, "Python"):

- :class:`Run` — a run directory: ``deck``, ``run_info``, ``profiles``, ``final_profile``,
  ``histories``, ``energy``, ``snapshots``, ``fragments``, ``spectra``, ``spectrum``,
  ``spectrum_detector``, ``xt``, and ``table(NAME)`` for any other CSV.
- :class:`Table` and :func:`read_csv` — one mscale CSV (title line, ``# units:`` line, header)
  as a numpy structured array with ``.units``, ``.title``, ``.time``; ``.to_pandas()``.
- :class:`Snapshot` and :func:`read_snapshot` — one particle snapshot (HDF5 via h5py), read
  lazily; ``.to_extxyz()``, ``.to_numpy()``, ``.to_pandas()``.
- :mod:`mscale.units` — the units' spellings and time conversion (``to_us``).

Needs numpy; h5py for HDF5 files, PyYAML for the YAML files, pandas only for ``to_pandas``.
"""
from .run import Arrays, Run, read_h5_group
from .snapshot import Snapshot, read_snapshot, species_of, write_extxyz
from .table import Table, read_csv
from .units import parse_units_line, to_us, us_per

import importlib.util as _util

#: pandas is optional: Tables and Snapshots convert with .to_pandas() when it is installed.
HAVE_PANDAS = _util.find_spec("pandas") is not None

__all__ = ["Run", "Table", "Snapshot", "Arrays", "read_csv", "read_snapshot", "read_h5_group",
           "write_extxyz", "species_of", "parse_units_line", "to_us", "us_per", "HAVE_PANDAS"]
