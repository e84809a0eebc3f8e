# SPDX-License-Identifier: MIT
"""tools/taylor_profile.py against the run's own measures.

    /usr/bin/python3 tests/python/test_taylor_profile.py MSCALE_BINARY SOURCE_DIR WORKDIR

Runs a small `impact` deck (a copper cylinder of radius 3 h and 12 layers at 0.3 km/s onto the
wall, 3 µs) and checks that the tool's length and footprint (read through python/mscale from
the last particle snapshot, particles_0001.h5, the final state) equal the ones
particles/dm/dm_impact.c wrote to impact_summary.csv, and that at t = 0 (particles_0000.h5) they
are the rod's L0 = 12 h and D0: the two implementations of docs/input-impact.md's definitions
agree. Tolerance: the summary is a CSV of 10 significant digits (core/csv.c), so 1e-8 relative.
"""
import os
import subprocess
import sys

mscale_bin, src, work = sys.argv[1:4]
sys.path.insert(0, os.path.join(src, "python"))
sys.path.insert(0, os.path.join(src, "tools"))
import mscale  # noqa: E402
import taylor_profile  # noqa: E402

os.makedirs(work, exist_ok=True)
# the shared small rod (tests/dm/data/impact_small_rod.yaml), run on to t = 0.3 with snapshots at
# t = 0 and of the final state only
deck = os.path.join(src, "tests/dm/data/impact_small_rod.yaml")
out = os.path.join(work, "taylor_small")
env = dict(os.environ, ASAN_OPTIONS=os.environ.get("ASAN_OPTIONS", "") + ":detect_leaks=0")
res = subprocess.run([mscale_bin, "run", deck, "-o", out, "--force", "--quiet",
                      "--set", "impact.t_end=0.3", "--set", "impact.output.particle_times=[0]"],
                     env=env,
                     capture_output=True, text=True)
if res.returncode != 0:
    sys.exit(f"test_taylor_profile: mscale run failed ({res.returncode}):\n{res.stderr}")
summary = mscale.Run(out).table("impact_summary")
m = taylor_profile.measure(out)
names = [os.path.basename(s.path) for s in mscale.Run(out).snapshots]
assert names == ["particles_0000.h5", "particles_0001.h5"], names  # t = 0, then the final state
m0 = taylor_profile.measure(out, 0)
rtol = 1e-8
checks = [
    (abs(m["length"] / float(summary["length"][0]) - 1) < rtol, "final length"),
    (abs(m["footprint"] / float(summary["footprint"][0]) - 1) < rtol, "final footprint"),
    (abs(m0["length"] / 0.6 - 1) < rtol, "initial length = 12 h"),
    (abs(m0["footprint"] / 0.3 - 1) < rtol, "initial footprint = D0"),
    (abs(m0["r"].max() / 0.15 - 1) < rtol, "initial profile radius = R0"),
    (m["footprint"] > m0["footprint"] and m["length"] < m0["length"], "the rod deformed"),
]
for ok, what in checks:
    if not ok:
        sys.exit(f"test_taylor_profile: {what}: tool {m} vs summary {summary}")
print(f"test_taylor_profile: {len(checks)} checks passed (L {m['length']:.6f} cm, "
      f"D {m['footprint']:.6f} cm)")
