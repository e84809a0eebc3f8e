#!/bin/bash
# SPDX-License-Identifier: MIT
# `mscale run` of the discrete model with response: eos (replicated on the ranks,
# particles/dm/dm_problem_finite.c) serially and under mpirun -np 2, 3: every CSV byte for byte
# and both snapshots equal by value (h5diff, no tolerance). Every rank steps every particle with
# the same arithmetic and rank 0 writes, so anything but identity is a bug (a file or a
# checkpoint row written by two ranks, a rank that diverged). Then restarts across rank counts
# (the checkpoint holds the whole state whatever the rank count): from the serial run's last
# checkpoint on 3 ranks, and from the 2-rank run's on 1 rank; and a failing step on 2 ranks
# reports once and leaves the serial run's last good state.
# usage: dm_fin_cli.sh MSCALE MPIEXEC DECK
source "$(dirname "$0")/cli_common.sh"
files="dm_fin_energy.csv dm_fin_profile_000.csv dm_fin_profile_001.csv dm_probes.csv"
same() { # DIR_A DIR_B WHAT [FIRST_SNAPSHOT]
  for f in $files; do cmp -s "$1/$f" "$2/$f" || { echo "FAIL: $f differs ($3)"; exit 1; }; done
  for k in ${4:-0} 1; do
    h5diff -q "$1/particles_000$k.h5" "$2/particles_000$k.h5" ||
      { echo "FAIL: particles_000$k.h5 differs ($3)"; exit 1; }
  done
}
"$mscale" run "$deck" -o "$work/serial" --quiet
for np in 2 3; do
  mpirun $np "$mscale" run "$deck" -o "$work/np$np" --quiet
  grep -q "on $np ranks" "$work/np$np/run.log" || { echo "np $np: no rank count in run.log"; exit 1; }
  same "$work/serial" "$work/np$np" "serial vs $np ranks"
done
files="dm_fin_energy.csv dm_fin_profile_001.csv dm_probes.csv" # written after the last checkpoint
mpirun 3 "$mscale" run "$deck" -o "$work/r3" --restart "$work/serial/dm_checkpoint.h5" --quiet
grep -q "restarted from" "$work/r3/run.log" || { echo "FAIL: no restart in the log"; exit 1; }
same "$work/serial" "$work/r3" "serial vs restart on 3 ranks" 1
"$mscale" run "$deck" -o "$work/r1" --restart "$work/np2/dm_checkpoint.h5" --quiet
same "$work/serial" "$work/r1" "serial vs 2-rank checkpoint restarted on 1 rank" 1
# a step that fails (a piston too fast for an inviscid step): exit 1 on every rank count, one
# report, the same last good state
sed -e 's/velocity: 0.3/velocity: 8.0/' -e 's/checkpoint_every: 60/checkpoint_every: 0/' \
  -e 's/  piston:/  viscosity: {quadratic: 0.0, linear: 0.0}\n  courant: 1.0\n  piston:/' "$deck" \
  > "$work/fails.yaml"
for np in 1 2; do
  rc=0
  mpirun $np "$mscale" run "$work/fails.yaml" -o "$work/fail$np" --quiet 2> "$work/fail$np.err" || rc=$?
  [ $rc == 1 ] || { cat "$work/fail$np.err"; echo "FAIL: exit $rc on $np ranks (expected 1)"; exit 1; }
  n=$(grep -c "the run stops" "$work/fail$np.err" || true)
  [ "$n" == 1 ] || { cat "$work/fail$np.err"; echo "FAIL: $n reports on $np ranks"; exit 1; }
done
h5diff -q "$work/fail1/particles_unstable.h5" "$work/fail2/particles_unstable.h5" ||
  { echo "FAIL: the last good state differs on 2 ranks"; exit 1; }
echo "OK: serial = 2 ranks = 3 ranks = restarts on 3 and 1 ranks; a failure on 2 ranks = serial"
