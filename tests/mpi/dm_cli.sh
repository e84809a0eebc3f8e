#!/bin/bash
# SPDX-License-Identifier: MIT
# `mscale run` of a discrete_model deck under mpirun (docs/mpi.md):
#  1. mpirun -np 2 gives the same dm_energy.csv, dm_probes.csv and summary numbers (all but the
#     timing and partition columns) as the serial run, byte for byte (the distributed model is
#     bitwise rank-count independent);
#  2. kill -9 while a run writes checkpoints every step (so the kill lands inside or next to a
#     write): the checkpoint left behind restarts (on 2 ranks) and ends byte-identical to the
#     uninterrupted run. Two kills at fixed delays, then up to six as soon as a write is seen in
#     progress (the .part file exists) until one leaves that .part behind (timing-dependent, so
#     not asserted; the .part case is asserted in test_dm_mpi).
# Usage: dm_cli.sh MSCALE MPIRUN DECK   (a shrunken copy of DECK is run: CI-sized)
set -u
MSCALE=$1; MPIRUN=$2; DECK=$3
MPI="$MPIRUN --oversubscribe --allow-run-as-root"
T=$(mktemp -d dm_cli.XXXXXX); T=$PWD/$T
fail=0
sed -e 's/hi: \[2.4, 1.6, 1.6\]/hi: [1.2, 0.8, 0.8]/' -e 's/steps: 300/steps: 150/' \
    -e 's/checkpoint_every: 100 /checkpoint_every: 1 /' "$DECK" > "$T/deck.yaml"
grep -q "checkpoint_every: 1 " "$T/deck.yaml" || { echo "FAIL: deck not shrunk"; exit 1; }
export OMP_NUM_THREADS=1

"$MSCALE" run "$T/deck.yaml" -o "$T/serial" --quiet 2> "$T/serial.err" || { cat "$T/serial.err"; echo "FAIL serial run"; exit 1; }
$MPI -np 2 "$MSCALE" run "$T/deck.yaml" -o "$T/np2" --quiet 2> "$T/np2.err" || { cat "$T/np2.err"; echo "FAIL np2 run"; exit 1; }
# summary columns: 1-7 counts, dt, omega dt; 11-24 errors, energies (8-10 timing; 25-30 ranks,
# partition, restart step)
summ() { tail -1 "$1/dm_summary.csv" | cut -d, -f1-7,11-24; }
for f in dm_energy.csv dm_probes.csv; do
  cmp -s "$T/serial/$f" "$T/np2/$f" || { echo "FAIL: $f differs between 1 and 2 ranks"; fail=1; }
done
[ "$(summ "$T/serial")" == "$(summ "$T/np2")" ] || { echo "FAIL: summaries differ:"; summ "$T/serial"; summ "$T/np2"; fail=1; }
grep "METIS edge cut" "$T/np2/run.log" | sed 's/^.*discrete/discrete/'

for trial in 1 2 3 4 5 6 7 8; do
  # trials 5-8 only until one has killed a writer inside a write
  [ $trial -gt 4 ] && [ -n "${mid_write:-}" ] && break
  D="$T/kill$trial"
  "$MSCALE" run "$T/deck.yaml" -o "$D" --quiet 2> "$D.err" &
  pid=$!
  # wait for the first checkpoint, then a moment more (different for each trial)
  for i in $(seq 1 400); do [ -f "$D/dm_checkpoint.h5" ] && break; sleep 0.01; done
  if [ $trial -le 2 ]; then
    sleep "0.0$((trial * 3))"
  else # poll for a write in progress and kill the writer inside it
    for i in $(seq 1 200000); do [ -f "$D/dm_checkpoint.h5.part" ] && break; done
  fi
  kill -9 $pid 2> /dev/null
  wait $pid 2> /dev/null
  killed_mid="no"; [ -f "$D/dm_checkpoint.h5.part" ] && killed_mid="yes (a .part file was left)" && mid_write=1
  step=$(grep -o "checkpoint at step [0-9]*" "$D/run.log" | tail -1)
  echo "kill $trial: last logged '$step'; killed inside a write: $killed_mid"
  if [ ! -f "$D/dm_checkpoint.h5" ]; then
    if grep -q "run completed" "$D/run.log"; then echo "kill $trial came after the end; skipped"; continue; fi
    echo "FAIL: no checkpoint after kill $trial"; fail=1; continue
  fi
  $MPI -np 2 "$MSCALE" run "$T/deck.yaml" --restart "$D/dm_checkpoint.h5" -o "$D.resumed" --quiet 2> "$D.resumed.err" \
    || { cat "$D.resumed.err"; echo "FAIL: restart $trial"; fail=1; continue; }
  for f in dm_energy.csv dm_probes.csv; do
    cmp -s "$T/serial/$f" "$D.resumed/$f" || { echo "FAIL: $f after kill $trial + restart differs"; fail=1; }
  done
  [ "$(summ "$T/serial")" == "$(summ "$D.resumed")" ] || { echo "FAIL: summary after restart $trial differs"; fail=1; }
  grep -o "restarted from .*" "$D.resumed/run.log"
done
[ $fail == 0 ] && { echo "OK"; rm -rf "$T"; }
exit $fail
