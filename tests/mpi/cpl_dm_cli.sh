#!/bin/bash
# SPDX-License-Identifier: MIT
# `mscale run` of the coupled problem on the finite-deformation discrete model (replicated on
# the ranks, particles/dm/dm_region.c) serially and under mpirun -np 2, 3: every CSV byte for
# byte and the last snapshot equal by value (h5diff, no tolerance). Every rank steps the same
# particles with the same arithmetic, so anything but identity is a bug (a rank that missed
# rank 0's velocities, a driven-layer force summed twice, a snapshot or checkpoint row written
# by two ranks). Then a restart on 2 ranks from the serial run's last checkpoint ends
# identical too (the checkpoint holds the whole region whatever the rank count).
# usage: cpl_dm_cli.sh MSCALE MPIEXEC DECK
source "$(dirname "$0")/cli_common.sh"
files="free_surface.csv spectrum.csv fragments.csv ejecta_mass.csv history_drive.csv"
same() { # DIR_A DIR_B WHAT
  for f in $files; do cmp -s "$1/$f" "$2/$f" || { echo "FAIL: $f differs ($3)"; exit 1; }; done
  h5diff -q "$1/particles_0002.h5" "$2/particles_0002.h5" ||
    { echo "FAIL: particles_0002.h5 differs ($3)"; exit 1; }
}
"$mscale" run "$deck" -o "$work/serial" --quiet
for np in 2 3; do
  mpirun $np "$mscale" run "$deck" -o "$work/np$np" --quiet
  grep -q "on $np ranks" "$work/np$np/run.log" || { echo "np $np: no rank count in run.log"; exit 1; }
  same "$work/serial" "$work/np$np" "serial vs $np ranks"
done
mpirun 2 "$mscale" run "$deck" -o "$work/restart" --restart "$work/serial/coupled_checkpoint.h5" \
  --quiet
grep -q "restarted from" "$work/restart/run.log" || { echo "FAIL: no restart in the log"; exit 1; }
same "$work/serial" "$work/restart" "serial vs restart on 2 ranks"
echo "OK: serial = 2 ranks = 3 ranks = restart on 2 ranks"
