# SPDX-License-Identifier: MIT
"""Tables: mscale's CSV files (and HDF5 groups of equal-length datasets) as numpy structured
arrays with units, convertible to pandas DataFrames.

An mscale CSV is::

    # a title line (what the table is, often "... at t = 1 us ...")
    # units: t [us], x [cm], u [km/s]
    t,x,u
    0,0.5,0
    ...

(core/csv.c writes it). ``read_csv`` reads it into a :class:`Table`.
"""
import os
import re

import numpy as np

from .units import INTERNAL_TIME, as_text, parse_units_line

# Columns that hold counts or indices: read as int64 when every value is a whole number.
INT_COLUMNS = frozenset({"cell", "node", "step", "steps", "id", "gid", "count", "g", "N_ge",
                         "fragments", "fragment", "fragment_id", "material", "particles",
                         "real_particles", "bonds", "ranks", "restart_step", "edge_cut",
                         "edge_cut_slab"})
# Units that mean "a number of things": such columns are read as int64 too when whole.
COUNT_UNITS = frozenset({"fragments", "clusters", "particles"})

# "t = 0.1 10us", "t = 0.146785 (10us)", "t = 0.2 (10 us), ..."
_TIME = re.compile(r"\bt = ([-+0-9.eE]+)(?:\s*\(([^)]*)\)|\s+([^\s,;()]+))?")


def _title_time(title):
    m = _TIME.search(title or "")
    if not m:
        return None, None
    try:
        value = float(m.group(1))
    except ValueError:
        return None, None
    unit = m.group(2) or m.group(3)
    # "t = 0.1 in ..." is not a unit; only a word that starts like one
    if unit and not re.match(r"^[0-9]*\s*[µu]?s$|^[0-9]*\s*[nm]s$", unit.strip()):
        unit = None
    return value, (unit.strip() if unit else None)


class Table:
    """One table: named columns (numpy arrays), their units and the table's title.

    ``table["x"]`` is a column (a numpy array), ``table.units["x"]`` its unit (``"cm"``),
    ``table.label("x")`` the axis label ``"x [cm]"``; ``len(table)`` is the number of rows,
    ``list(table)`` the column names. ``table.data`` is the numpy structured array (one field
    per column: float64, or int64 for counts and indices), ``table.to_pandas()`` a DataFrame
    whose ``attrs`` hold the units and the title; ``table.attrs`` are the attributes of the
    HDF5 group a table was read from ({} for a CSV). ``table.time`` is the time the title names
    (``"... at t = 0.1 10us"`` -> 0.1), in ``table.time_unit``; None when the title names none.
    """

    def __init__(self, data, units=None, title="", path=None, comments=None, attrs=None):
        self.data = data
        self.attrs = dict(attrs or {})  # an HDF5 group's attributes (a history's node)
        self.units = dict(units or {})
        self.title = title or ""
        self.path = path
        self.comments = list(comments) if comments is not None else ([title] if title else [])
        self.time, self.time_unit = _title_time(self.title)
        if self.time is not None and self.time_unit is None:
            self.time_unit = self.units.get("t", INTERNAL_TIME)

    # -- columns -------------------------------------------------------------------------
    @property
    def names(self):
        """The column names, in file order."""
        return tuple(self.data.dtype.names or ())

    def keys(self):
        return self.names

    def __iter__(self):
        return iter(self.names)

    def __contains__(self, name):
        return name in self.names

    def __len__(self):
        return len(self.data)

    def __getitem__(self, key):
        """A column by name (a numpy array); one row by an integer index (a numpy record);
        a new Table of the rows a slice, boolean mask or index array selects."""
        if isinstance(key, str):
            if key not in self.names:
                raise KeyError(f"{self.name}: no column '{key}' (columns: {', '.join(self.names)})")
            return self.data[key]
        if isinstance(key, (int, np.integer)):
            return self.data[key]
        return self.select(key)

    @property
    def name(self):
        """The file's name without the extension ("profile_0001"), or the title."""
        return os.path.splitext(os.path.basename(self.path))[0] if self.path else self.title

    def unit(self, name):
        """The unit of column ``name`` ("1" when the file names none)."""
        return self.units.get(name, "1")

    def label(self, name):
        """An axis label: "name [unit]", or the bare name when the file gives no unit."""
        return f"{name} [{self.units[name]}]" if name in self.units else name

    # -- conversions ---------------------------------------------------------------------
    def to_numpy(self):
        """The numpy structured array (the same object as ``self.data``)."""
        return self.data

    def to_pandas(self):
        """A pandas DataFrame of the columns (vector columns split into NAME_0, NAME_1, ...);
        ``df.attrs["units"]`` maps column names to units, ``df.attrs["title"]`` is the title.
        Raises ImportError when pandas is not installed (Debian: python3-pandas)."""
        import pandas as pd

        cols, units = {}, {}
        for n in self.names:
            col = self.data[n]
            if col.ndim == 1:
                cols[n], units[n] = col, self.unit(n)
            else:
                for k in range(col.shape[1]):
                    cols[f"{n}_{k}"], units[f"{n}_{k}"] = col[:, k], self.unit(n)
        df = pd.DataFrame(cols)
        df.attrs["units"] = units
        df.attrs["title"] = self.title
        if self.time is not None:
            df.attrs["time"], df.attrs["time_unit"] = self.time, self.time_unit
        return df

    def select(self, mask, title=None):
        """A new Table of the rows ``mask`` (a boolean mask, slice or index array) selects, with
        the same units and title."""
        return Table(self.data[mask], self.units, self.title if title is None else title,
                     self.path, self.comments, self.attrs)

    def __repr__(self):
        cols = ", ".join(f"{n} [{self.unit(n)}]" for n in self.names)
        return f"<mscale.Table {self.name}: {len(self)} rows; {cols}>"

    # -- readers -------------------------------------------------------------------------
    @classmethod
    def from_columns(cls, columns, units=None, title="", path=None):
        """A Table from a dict name -> 1D (or [n][k]) array, all with the same first length."""
        names = list(columns)
        arrays = [np.asarray(columns[n]) for n in names]
        nrow = len(arrays[0]) if arrays else 0
        if any(len(a) != nrow for a in arrays):
            raise ValueError(f"{path or title}: columns of different lengths")
        dtype = [(n, a.dtype, a.shape[1:]) if a.ndim > 1 else (n, a.dtype)
                 for n, a in zip(names, arrays)]
        data = np.empty(nrow, dtype=dtype)
        for n, a in zip(names, arrays):
            data[n] = a
        return cls(data, units, title, path)

    @classmethod
    def from_h5_group(cls, group, title=None, path=None):
        """A Table of the datasets of an h5py group that share their first dimension (units
        from each dataset's ``units`` attribute). Other datasets are left out."""
        items = sorted((n, d) for n, d in group.items() if hasattr(d, "shape") and d.ndim >= 1)
        if not items:
            return cls.from_columns({}, {}, title or group.name, path)
        nrow = max(len(d) for _, d in items)
        cols, units = {}, {}
        for n, d in items:
            if len(d) == nrow and d.ndim <= 2:
                cols[n] = d[()]
                u = as_text(d.attrs.get("units"))
                if u is not None:
                    units[n] = u
        table = cls.from_columns(cols, units, title or group.name.strip("/"), path)
        table.attrs = {k: (as_text(v) if isinstance(v, (bytes, np.bytes_)) else
                           (v.item() if isinstance(v, np.generic) else v))
                       for k, v in group.attrs.items()}
        return table


def read_csv(path):
    """Read one mscale CSV file into a :class:`Table` (units from its ``# units:`` line).

    Counts and indices (``cell``, ``id``, ``count``, ``g``, ``material``, ... and columns whose
    unit is fragments, clusters or particles) are int64 when every value is a whole number;
    every other column is float64. A table with a header and no rows gives zero-length
    columns. Raises ValueError on a file without a header line or with ragged rows.
    """
    with open(path) as f:
        lines = f.read().splitlines()
    comments = [ln[1:].strip() for ln in lines if ln.startswith("#")]
    units = {}
    for c in comments:
        if c.startswith("units:"):
            units.update(parse_units_line(c))
    title = next((c for c in comments if not c.startswith("units:")), "")
    body = [ln for ln in lines if ln.strip() and not ln.startswith("#")]
    if not body:
        raise ValueError(f"{path}: no header line")
    names = [n.strip() for n in body[0].split(",")]
    rows = body[1:]
    if rows:
        values = np.loadtxt(rows, delimiter=",", ndmin=2, dtype=np.float64)
        if values.shape[1] != len(names):
            raise ValueError(f"{path}: {values.shape[1]} values per row, {len(names)} names")
    else:
        values = np.zeros((0, len(names)))
    cols = {}
    for k, n in enumerate(names):
        col = values[:, k]
        whole = (n in INT_COLUMNS or units.get(n) in COUNT_UNITS) and np.all(np.isfinite(col)) \
            and np.all(col == np.round(col)) and np.all(np.abs(col) < 2.0 ** 53)
        cols[n] = col.astype(np.int64) if whole else col
    table = Table.from_columns(cols, units, title, path)
    table.comments = comments
    return table
