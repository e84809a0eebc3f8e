#!/bin/bash
# SPDX-License-Identifier: MIT
# Fragment outputs of a cluster-dynamics run on MPI ranks equal the serial ones (docs/mpi.md
# "Fragments on MPI ranks"): inputs/cd-grooves-2d.yaml run to t = 6e-3 (3210 steps; a jet tip
# breaks off the grooved surface: fragments of 4 and 1853 particles) serially and under
# mpirun -np 2; `mscale spectrum --fragments` of the last snapshots (periodic in x: the
# snapshot's period_x attribute; stored in gid order
# serially, in rank order under MPI: numbering by smallest gid makes them comparable) must give
# the same spectrum (byte for byte) and the same fragment table: ids, counts and masses as
# printed, centres, velocities and R_g within 1e-9 of the column scale or of 0.01 cm / 1 km/s
# (the runs differ by round-off in the force sums, ~1e-13 here). The largest fragment, the
# sample, spans the periodic width: its x centre (a circular mean of a full ring of particles)
# and its R_g are not defined to round-off, so they are left out.
# usage: frag_cli.sh MSCALE MPIEXEC DECK
source "$(dirname "$0")/cli_common.sh"
src=$(cd "$(dirname "$deck")" && pwd)
sed -e "s#file: \.\./eos#file: $src/../eos#" -e 's/t_end: 3.0e-3/t_end: 6.0e-3/' \
    -e 's/snapshots: 3}/snapshots: 1}/' "$deck" > "$work/deck.yaml"
grep -q "t_end: 6.0e-3" "$work/deck.yaml" || { echo "deck edit failed"; exit 1; }
"$mscale" run "$work/deck.yaml" -o "$work/np1" --quiet
mpirun 2 "$mscale" run "$work/deck.yaml" -o "$work/np2" --quiet
for np in 1 2; do
  snap=$(ls "$work/np$np"/particles_[0-9]*.h5 | tail -1)
  h5dump -a /particles/period_x "$snap" | grep -q "0.01" || { echo "no period_x"; exit 1; }
  "$mscale" spectrum "$snap" --fragments "$work/frag$np.csv" |
    grep -v '^#' > "$work/spec$np.csv"
done
diff "$work/spec1.csv" "$work/spec2.csv"
/usr/bin/python3 - "$work/frag1.csv" "$work/frag2.csv" <<'PY'
import sys
import numpy as np
def table(path):
    lines = [l for l in open(path) if not l.startswith("#")]
    return np.genfromtxt(lines, delimiter=",", names=True)
a, b = table(sys.argv[1]), table(sys.argv[2])
assert a.shape == b.shape and a.size >= 2, (a.shape, b.shape)
for col in ("id", "count", "mass"):
    assert (a[col] == b[col]).all(), col
small = a["count"] < a["count"].max()
for col, unit in (("x", 0.01), ("y", 0.01), ("z", 0.01), ("vx", 1), ("vy", 1), ("vz", 1), ("rg", 0.01)):
    keep = small if col in ("x", "rg") else np.ones(a.size, bool)
    scale = max(np.abs(a[col]).max(), unit)
    err = np.abs(a[col] - b[col])[keep].max() / scale
    assert err < 1e-9, (col, err)
print(f"frag_cli: {a.size} fragments, counts {sorted(a['count'].astype(int))}: same on 2 ranks")
PY
echo "frag_cli: OK"
