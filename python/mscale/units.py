# SPDX-License-Identifier: MIT
"""Units as mscale writes them, and the few conversions the plots need.

Every mscale output names its units: a CSV table in its ``# units: name [unit], ...`` line, an
HDF5 dataset in its ``units`` attribute (profiles add ``time_units`` on the file). The internal
system is g, cm, 10 µs (docs/design.md §2), so velocities are km/s, pressures GPa and densities
g/cm^3; outputs give times in µs ("us"; files of mscale before the unit change say "10us"),
and every reader takes the unit the file names.
"""
import re

#: The internal time unit (docs/design.md §2), used when an output does not name one.
INTERNAL_TIME = "10us"

# microseconds per unit, for the spellings mscale writes ("10us", "10 us") and the usual ones
_US_PER = {
    "10us": 10.0, "10 us": 10.0, "10µs": 10.0, "10 µs": 10.0,
    "us": 1.0, "µs": 1.0, "microsecond": 1.0, "microseconds": 1.0,
    "ns": 1e-3, "ms": 1e3, "s": 1e6,
}

_ITEM = re.compile(r"\s*(.*?)\s*\[([^\]]*)\]\s*(?:,|$)")


def parse_units_line(line):
    """The units of a CSV ``units:`` comment, as a dict name -> unit.

    >>> parse_units_line("units: t [10us], x [cm], w_x(0.5) [cm]")
    {'t': '10us', 'x': 'cm', 'w_x(0.5)': 'cm'}
    """
    text = line.strip().lstrip("#").strip()
    if text.startswith("units:"):
        text = text[len("units:"):]
    return {m.group(1): m.group(2).strip() for m in _ITEM.finditer(text) if m.group(1)}


def as_text(value):
    """An HDF5 string attribute (bytes, numpy bytes or str) as a str; None stays None."""
    if value is None:
        return None
    if hasattr(value, "tobytes") and getattr(value, "dtype", None) is not None \
            and value.dtype.kind == "S":
        value = value.tobytes()
    if isinstance(value, bytes):
        return value.decode("utf-8", "replace").rstrip("\0")
    return str(value)


def us_per(unit):
    """Microseconds per one ``unit`` of time (``"10us"`` -> 10.0); ValueError if unknown."""
    key = (unit or INTERNAL_TIME).strip()
    if key in _US_PER:
        return _US_PER[key]
    raise ValueError(f"unknown time unit '{unit}'")


def to_us(value, unit):
    """A time (scalar or numpy array) in ``unit`` converted to microseconds."""
    return value * us_per(unit)
