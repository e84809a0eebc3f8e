#!/bin/bash
# `mscale run` of a shrunken inputs/cd-piston-al.yaml (bonded cutoff, thermal noise, piston,
# periodic x/y, free z) serially and under mpirun -np 2 and 3 (docs/mpi.md, "Cluster dynamics
# on MPI ranks"): the CSV files must agree with the serial ones to the printed digits (relative
# 1e-8: the runs differ by summation order only, ~1e-13 after these steps), the snapshot must
# hold every particle exactly once, and the log must report the decomposition.
# usage: cd_cli.sh MSCALE MPIEXEC DECK
set -euo pipefail
mscale=$1 mpiexec=$2 deck=$3
work=$(mktemp -d)
trap 'rm -rf "$work"' EXIT
src=$(cd "$(dirname "$deck")" && pwd)
# 6x6x28 a (~4000 particles), 300 steps, one snapshot at the end
sed -e "s#file: \.\./eos#file: $src/../eos#" -e 's/t_end: 4.0e-3 /t_end: 5.6e-4 /' \
    -e 's/hi: \[4.2426406871192851e-3, 4.2426406871192851e-3, 0.1\]/hi: [4.2426406871192851e-3, 4.2426406871192851e-3, 0.02]/' \
    -e 's/snapshots: 4}/snapshots: 1}/' "$deck" > "$work/deck.yaml"
grep -q "0.02]" "$work/deck.yaml" || { echo "deck edit failed"; exit 1; }
export OMP_NUM_THREADS=1
"$mscale" run "$work/deck.yaml" -o "$work/np1" --quiet
for np in 2 3; do
  "$mpiexec" --oversubscribe --allow-run-as-root -np $np "$mscale" run "$work/deck.yaml" \
    -o "$work/np$np" --quiet
  grep -q "cluster_dynamics on $np ranks:.*coarse cells" "$work/np$np/run.log" ||
    { echo "np $np: no decomposition line in run.log"; exit 1; }
  /usr/bin/python3 - "$work/np1" "$work/np$np" <<'EOF'
import sys, glob, os
import numpy as np, h5py
a, b = sys.argv[1], sys.argv[2]
for f in ("cd_energy.csv", "cd_profiles.csv", "cd_front.csv"):
    x = np.genfromtxt(os.path.join(a, f), delimiter=",", comments="#", skip_header=0)
    y = np.genfromtxt(os.path.join(b, f), delimiter=",", comments="#", skip_header=0)
    x, y = x[np.isfinite(x).all(axis=1)], y[np.isfinite(y).all(axis=1)]
    assert x.shape == y.shape, (f, x.shape, y.shape)
    scale = np.maximum(np.abs(x).max(axis=0), 1e-300)
    err = (np.abs(x - y) / scale).max()
    print(f"{b}: {f} max deviation {err:.2e} of the column scale")
    assert err < 1e-8, (f, err)
snaps = sorted(glob.glob(os.path.join(b, "cd_snap_*.h5")))
ref = sorted(glob.glob(os.path.join(a, "cd_snap_*.h5")))
assert snaps and len(snaps) == len(ref), (snaps, ref)
with h5py.File(snaps[-1]) as h, h5py.File(ref[-1]) as r:
    g, gr = h["particles/gid"][:], r["particles/gid"][:]
    assert len(g) == len(gr) and len(np.unique(g)) == len(g), "gids"
    order, order_r = np.argsort(g), np.argsort(gr)
    assert (g[order] == gr[order_r]).all()
    dx = np.abs(h["particles/x"][:][order] - r["particles/x"][:][order_r]).max()
    print(f"{b}: snapshot of {len(g)} particles, max |dx| {dx:.2e} cm")
    assert dx < 1e-12, dx
EOF
done
echo "cd_cli: OK"
