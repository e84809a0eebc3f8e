#!/bin/bash
# SPDX-License-Identifier: MIT
# `mscale run` of a shrunken inputs/cd-piston-al.yaml (bonded cutoff, thermal noise, piston,
# periodic x/y, free z) serially and under mpirun -np 2 and 3 (docs/mpi.md, "Cluster dynamics
# on MPI ranks"): the CSV files must agree with the serial ones to the printed digits (relative
# 1e-8: the runs differ by summation order only; compare_cd_runs.py), the snapshot must
# hold every particle exactly once, and the log must report the decomposition.
# usage: cd_cli.sh MSCALE MPIEXEC DECK
source "$(dirname "$0")/cli_common.sh"
src=$(cd "$(dirname "$deck")" && pwd)
# 6x6x28 a (~4000 particles), 300 steps, one snapshot at the end
sed -e "s#file: \.\./eos#file: $src/../eos#" -e 's/t_end: 4.0e-3 /t_end: 5.6e-4 /' \
    -e 's/hi: \[4.2426406871192851e-3, 4.2426406871192851e-3, 0.1\]/hi: [4.2426406871192851e-3, 4.2426406871192851e-3, 0.02]/' \
    -e 's/snapshots: 4}/snapshots: 1}/' "$deck" > "$work/deck.yaml"
grep -q "0.02]" "$work/deck.yaml" || { echo "deck edit failed"; exit 1; }
"$mscale" run "$work/deck.yaml" -o "$work/np1" --quiet
for np in 2 3; do
  mpirun $np "$mscale" run "$work/deck.yaml" -o "$work/np$np" --quiet
  grep -q "cluster_dynamics on $np ranks:.*coarse cells" "$work/np$np/run.log" ||
    { echo "np $np: no decomposition line in run.log"; exit 1; }
  /usr/bin/python3 "$(dirname "$0")/compare_cd_runs.py" "$work/np1" "$work/np$np"
done
echo "cd_cli: OK"
