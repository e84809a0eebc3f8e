#!/bin/bash
# SPDX-License-Identifier: MIT
# `mscale run` of an `impact` deck (replicated on the ranks, particles/dm/dm_impact_run.h)
# serially and under mpirun -np 2, 3: impact_history.csv byte for byte, impact_summary.csv but
# its wall_time column byte for byte, every snapshot and the last checkpoint's data by value
# (h5diff, no tolerance; the checkpoint's root attribute `ranks` differs by design). Every rank
# steps every particle with the same arithmetic and rank 0 writes, so anything but identity is a
# bug (a file or a checkpoint row written by two ranks, a rank that diverged). Then restarts
# across rank counts: the serial run's last checkpoint on 3 ranks, the 2-rank run's on 1 rank.
# usage: impact_cli.sh MSCALE MPIEXEC DECK
source "$(dirname "$0")/cli_common.sh"
same() { # DIR_A DIR_B WHAT: the snapshots DIR_B has
  cmp -s "$1/impact_history.csv" "$2/impact_history.csv" ||
    { echo "FAIL: impact_history.csv differs ($3)"; exit 1; }
  cmp -s <(cut -d, -f5 --complement "$1/impact_summary.csv") \
    <(cut -d, -f5 --complement "$2/impact_summary.csv") ||
    { echo "FAIL: impact_summary.csv differs beyond wall_time ($3)"; exit 1; }
  for f in "$2"/particles_[0-9]*.h5; do
    h5diff -q "$1/$(basename "$f")" "$f" || { echo "FAIL: $(basename "$f") differs ($3)"; exit 1; }
  done
}
"$mscale" run "$deck" -o "$work/serial" --quiet
ls "$work"/serial/particles_000[0-9].h5 > /dev/null
for np in 2 3; do
  mpirun $np "$mscale" run "$deck" -o "$work/np$np" --quiet
  grep -q "impact on $np ranks" "$work/np$np/run.log" || { echo "np $np: no rank count in run.log"; exit 1; }
  same "$work/serial" "$work/np$np" "serial vs $np ranks"
  cmp -s "$work/serial/particles.xmf" "$work/np$np/particles.xmf" ||
    { echo "FAIL: particles.xmf differs (serial vs $np ranks)"; exit 1; }
  for g in dm_fin impact; do
    h5diff -q "$work/serial/impact_checkpoint.h5" "$work/np$np/impact_checkpoint.h5" "/$g" "/$g" ||
      { echo "FAIL: the checkpoint's /$g differs (serial vs $np ranks)"; exit 1; }
  done
done
mpirun 3 "$mscale" run "$deck" -o "$work/r3" --restart "$work/serial/impact_checkpoint.h5" --quiet
grep -q "restarted from" "$work/r3/run.log" || { echo "FAIL: no restart in the log"; exit 1; }
same "$work/serial" "$work/r3" "serial vs the serial checkpoint restarted on 3 ranks"
"$mscale" run "$deck" -o "$work/r1" --restart "$work/np2/impact_checkpoint.h5" --quiet
same "$work/serial" "$work/r1" "serial vs the 2-rank checkpoint restarted on 1 rank"
echo "OK: serial = 2 ranks = 3 ranks (outputs and checkpoint); restarts on 3 and 1 ranks = serial"
