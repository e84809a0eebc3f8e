#!/bin/bash
# SPDX-License-Identifier: MIT
# Checkpoint/restart of cluster_dynamics under mpirun (docs/mpi.md, "Checkpoint/restart"):
#  1. on 2 ranks: run to the end; run to half-way, restart from its checkpoint to the end: the
#     CSV files and the final snapshot are byte-identical (the checkpoint holds the coarse-cell
#     owner map, so every rank gets its particles back in their order);
#  2. that checkpoint restarted on 1 and on 3 ranks: the CSV files agree with the 2-rank run to
#     relative 1e-8 of each column's scale and the snapshot positions to 1e-12 cm (the runs then
#     differ by force summation order only, as any two rank counts: ~1e-13 after these steps).
# usage: cd_restart_mpi.sh MSCALE MPIEXEC DECK
source "$(dirname "$0")/cli_common.sh"
mpi() { np=$1; shift; mpirun "$np" "$mscale" run "$@" --quiet; }
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
h5diff -q "$work/full/particles_0002.h5" "$work/cont2/particles_0002.h5" ||
  { echo "FAIL: the final snapshot differs after a restart on 2 ranks"; exit 1; }
echo "2 ranks -> 2 ranks: bitwise"
for np in 1 3; do
  /usr/bin/python3 "$(dirname "$0")/compare_cd_runs.py" "$work/full" "$work/cont$np"
done
echo "cd_restart_mpi: OK"
