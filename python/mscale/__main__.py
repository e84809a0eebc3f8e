# SPDX-License-Identifier: MIT
"""``PYTHONPATH=python /usr/bin/python3 -m mscale RUNDIR...``: what a run directory holds, as
the package reads it (problem, status, every table with its rows and units, the snapshots)."""
import sys

from . import Run


def summary(path):
    """The lines describing one run directory."""
    run = Run(path)
    info = run.run_info or {}
    out = [f"{path}: problem {run.problem}, status {info.get('status', '?')}, "
           f"{info.get('ranks', '?')} rank(s), {info.get('wall_time_s', '?')} s"]
    for name, t in run.tables.items():
        out.append(f"  {name}: {len(t)} rows; " + ", ".join(f"{n} [{t.unit(n)}]" for n in t))
    for s in run.snapshots:
        out.append(f"  {s.name}: {len(s)} particles at t = {s.time:.6g} {s.time_unit}; "
                   + ", ".join(s.keys()))
    if run.xt is not None:
        out.append("  xt: " + ", ".join(f"{k} {v.shape}" for k, v in run.xt.items()))
    return out


def main(argv):
    if len(argv) < 2 or argv[1] in ("-h", "--help"):
        print(__doc__)
        return 0 if len(argv) >= 2 else 2
    rc = 0
    for path in argv[1:]:
        try:
            print("\n".join(summary(path)))
        except (OSError, ValueError) as exc:
            print(f"mscale: {exc}", file=sys.stderr)
            rc = 2
    return rc


if __name__ == "__main__":
    sys.exit(main(sys.argv))
