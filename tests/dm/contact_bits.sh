#!/usr/bin/env bash
# SPDX-License-Identifier: MIT
# The short-range contact keeps the bits of a run in which no pair outside the families comes
# within its seeing distance (particles/dm/dm_contact.c): the coupled spall deck on the discrete
# model with the contact on (the default 0.5 spacing) and off gives the same output bytes.
# Usage: contact_bits.sh MSCALE DECK
set -euo pipefail
mscale=$1
deck=$2
work=$(mktemp -d)
trap 'rm -rf "$work"' EXIT
# Under the sanitizer build: Open MPI's start-up leaks in its dlopen'ed components, which
# LeakSanitizer cannot suppress by name (as tests/restart_check.sh); address/UB errors still stop.
export ASAN_OPTIONS="${ASAN_OPTIONS:-}:detect_leaks=0"
run() { # run OUT [--set ...]: a failed run prints its log and fails the test
  OMP_NUM_THREADS=1 "$mscale" run "$deck" -o "$@" >"$work/log" 2>&1 || {
    echo "mscale run failed:"; tail -20 "$work/log"; exit 1; }
}
run "$work/on"
run "$work/off" --set coupled.particles.contact_distance=0
n=0
for f in "$work"/on/*.csv; do
  b=$(basename "$f")
  cmp -s "$f" "$work/off/$b" || { echo "differs with the contact on: $b"; exit 1; }
  n=$((n + 1))
done
[ "$n" -gt 5 ] || { echo "too few outputs ($n)"; exit 1; }
echo "contact on/off: $n output files identical"
