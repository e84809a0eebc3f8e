#!/bin/bash
# Checkpoint/restart of cluster_dynamics under mpirun (docs/mpi.md, "Checkpoint/restart"):
#  1. on 2 ranks: run to the end; run to half-way, restart from its checkpoint to the end: the
#     CSV files and the final snapshot are byte-identical (the checkpoint holds the coarse-cell
#     owner map, so every rank gets its particles back in their order);
#  2. that checkpoint restarted on 1 and on 3 ranks: the CSV files agree with the 2-rank run to
#     relative 1e-8 of each column's scale and the snapshot positions to 1e-12 cm (the runs then
#     differ by force summation order only, as any two rank counts: ~1e-13 after these steps).
# usage: cd_restart_mpi.sh MSCALE MPIEXEC DECK
set -euo pipefail
mscale=$1 mpiexec=$2 deck=$3
work=$(mktemp -d)
trap 'rm -rf "$work"' EXIT
export OMP_NUM_THREADS=1
mpi() { np=$1; shift; "$mpiexec" --oversubscribe --allow-run-as-root -np "$np" "$mscale" run "$@" --quiet; }
sed -e 's/t_end: 1.5e-3/t_end: 7.5e-4/' "$deck" > "$work/half.yaml"
mpi 2 "$deck" -o "$work/full"
mpi 2 "$work/half.yaml" -o "$work/half"
for np in 2 1 3; do
  mpi $np "$deck" -o "$work/cont$np" --restart "$work/half/cd_checkpoint.h5"
  grep -o "restarted from .*" "$work/cont$np/run.log"
done
for f in cd_energy.csv cd_profiles.csv cd_front.csv; do
  cmp "$work/full/$f" "$work/cont2/$f" || { echo "FAIL: $f differs after a restart on 2 ranks"; exit 1; }
done
h5diff -q "$work/full/cd_snap_000803.h5" "$work/cont2/cd_snap_000803.h5" ||
  { echo "FAIL: the final snapshot differs after a restart on 2 ranks"; exit 1; }
echo "2 ranks -> 2 ranks: bitwise"
for np in 1 3; do
  /usr/bin/python3 - "$work/full" "$work/cont$np" <<'EOF'
import sys, os
import numpy as np, h5py
a, b = sys.argv[1], sys.argv[2]
for f in ("cd_energy.csv", "cd_profiles.csv", "cd_front.csv"):
    x = np.genfromtxt(os.path.join(a, f), delimiter=",", comments="#")
    y = np.genfromtxt(os.path.join(b, f), delimiter=",", comments="#")
    x, y = x[np.isfinite(x).all(axis=1)], y[np.isfinite(y).all(axis=1)]
    assert x.shape == y.shape, (f, x.shape, y.shape)
    err = (np.abs(x - y) / np.maximum(np.abs(x).max(axis=0), 1e-300)).max()
    print(f"{os.path.basename(b)}: {f} max deviation {err:.2e} of the column scale")
    assert err < 1e-8, (f, err)
with h5py.File(os.path.join(b, "cd_snap_000803.h5")) as h, \
     h5py.File(os.path.join(a, "cd_snap_000803.h5")) as r:
    g, gr = h["particles/gid"][:], r["particles/gid"][:]
    assert len(g) == len(gr) and len(np.unique(g)) == len(g), "gids"
    o, orr = np.argsort(g), np.argsort(gr)
    assert (g[o] == gr[orr]).all()
    dx = np.abs(h["particles/x"][:][o] - r["particles/x"][:][orr]).max()
    print(f"{os.path.basename(b)}: snapshot of {len(g)} particles, max |dx| {dx:.2e} cm")
    assert dx < 1e-12, dx
EOF
done
echo "cd_restart_mpi: OK"
