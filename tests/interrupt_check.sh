#!/bin/bash
# SPDX-License-Identifier: MIT
# Interrupts and --continue (docs/reliability.md "Interrupts"):
#  1. the deck runs to its end (checkpoints on) -> full/;
#  2. the same run -> cut/, with run_info.yaml saying `status: running` while it runs; SIGTERM
#     to every rank once its first checkpoint exists (as a batch system sends it; mpirun itself
#     would kill its ranks instead of passing the signal on):
#     the run stops at its next checkpoint, exit 1, `status: interrupted`, no .part file left;
#  3. `mscale run DECK -o cut --continue` goes on from cut/'s own checkpoint: FILES must then be
#     byte-identical to full/'s (CSV with cmp, HDF5 with h5diff), as the restart tests require.
# Usage: interrupt_check.sh MSCALE DECK CKPT RANKS FILE...
set -u
MSCALE=$1; DECK=$2; CKPT=$3; RANKS=$4; shift 4; FILES="$*"
T=$(mktemp -d interrupt.XXXXXX); T=$PWD/$T
export OMP_NUM_THREADS=1
export ASAN_OPTIONS="${ASAN_OPTIONS:-}:detect_leaks=0" # Open MPI's start-up leaks (restart_check.sh)
launch=()
if [ "$RANKS" -gt 1 ]; then
  launch=(mpirun --oversubscribe -np "$RANKS")
  [ "$(id -u)" = 0 ] && launch+=(--allow-run-as-root)
fi
fail=0
cp "$DECK" "$T/deck.yaml"
"${launch[@]}" "$MSCALE" run "$T/deck.yaml" -o "$T/full" --quiet 2>> "$T/stderr" ||
  { cat "$T/stderr"; echo "FAIL: full run"; exit 1; }

"${launch[@]}" "$MSCALE" run "$T/deck.yaml" -o "$T/cut" --quiet 2>> "$T/stderr" &
pid=$!
for i in $(seq 1 3000); do [ -f "$T/cut/$CKPT" ] && break; sleep 0.01; done
[ -f "$T/cut/$CKPT" ] || { echo "FAIL: no first checkpoint within 30 s"; kill -9 $pid; exit 1; }
grep -q "^status: running" "$T/cut/run_info.yaml" ||
  { echo "FAIL: run_info.yaml does not say 'status: running' during the run"; fail=1; }
if [ "$RANKS" -gt 1 ]; then pkill -TERM -P $pid; else kill -TERM $pid; fi
wait $pid; rc=$?
[ $rc = 1 ] || { echo "FAIL: the interrupted run exited $rc, not 1"; fail=1; }
grep -q "^status: interrupted" "$T/cut/run_info.yaml" ||
  { echo "FAIL: run_info.yaml does not say 'status: interrupted'"; cat "$T/cut/run_info.yaml"; fail=1; }
ls "$T/cut"/*.part > /dev/null 2>&1 && { echo "FAIL: .part files left"; fail=1; }
grep -o "interrupted; checkpoint at [a-z ]*step [0-9]*" "$T/cut/run.log" | head -1

"${launch[@]}" "$MSCALE" run "$T/deck.yaml" -o "$T/cut" --continue --quiet 2>> "$T/stderr" ||
  { cat "$T/stderr"; echo "FAIL: --continue"; exit 1; }
grep -q "^status: completed" "$T/cut/run_info.yaml" || { echo "FAIL: not completed"; fail=1; }
for f in $FILES; do
  case $f in
    *.h5) h5diff -q "$T/full/$f" "$T/cut/$f" > /dev/null 2>&1 ;;
    *) cmp -s "$T/full/$f" "$T/cut/$f" ;;
  esac || { echo "FAIL: $f differs between the uninterrupted and the interrupted + continued run"; fail=1; }
done
[ $fail = 0 ] && echo "interrupt_check: interrupted at a checkpoint, continued, identical ($RANKS rank(s))" && rm -rf "$T"
exit $fail
