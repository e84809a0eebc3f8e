#!/bin/bash
# SPDX-License-Identifier: MIT
# SIGTERM to an `impact` run (a problem type without checkpoints; docs/reliability.md
# "Interrupts"): it stops at its next step with exit 1, `status: interrupted`, no .part file,
# and its message offers `--force` (a fresh start), not `--continue` (there is nothing to
# continue from). Usage: impact_interrupt.sh MSCALE DECK
set -u
MSCALE=$1; DECK=$2
T=$(mktemp -d impact_interrupt.XXXXXX); T=$PWD/$T
export OMP_NUM_THREADS=1 ASAN_OPTIONS="${ASAN_OPTIONS:-}:detect_leaks=0"
"$MSCALE" run "$DECK" -o "$T/cut" > "$T/stderr" 2>&1 &
pid=$!
for i in $(seq 1 3000); do grep -q "^status: running" "$T/cut/run_info.yaml" 2>/dev/null && break; sleep 0.01; done
sleep 0.5 # into the time loop
kill -TERM $pid
wait $pid; rc=$?
fail=0
[ $rc = 1 ] || { echo "FAIL: the interrupted run exited $rc, not 1"; fail=1; }
grep -q "^status: interrupted" "$T/cut/run_info.yaml" ||
  { echo "FAIL: run_info.yaml does not say 'status: interrupted'"; fail=1; }
ls "$T/cut"/*.part > /dev/null 2>&1 && { echo "FAIL: .part files left"; fail=1; }
grep -q -- "--force. starts it again" "$T/stderr" ||
  { echo "FAIL: the message does not offer --force"; cat "$T/stderr"; fail=1; }
grep -q -- "--continue" "$T/stderr" && { echo "FAIL: the message offers --continue"; fail=1; }
[ $fail = 0 ] && echo "impact_interrupt: stopped, status interrupted, --force offered" && rm -rf "$T"
exit $fail
