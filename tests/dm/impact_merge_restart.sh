#!/bin/bash
# SPDX-License-Identifier: MIT
# Restart after reference updates that keep the families (impact.reference_update.families:
# keep | merge, scope: all | family): the checkpoint stores the families as they are (their
# bonds, each family's own bond vectors, A⁻¹, κ; dm_family_checkpoint.c), so a run continued
# from a checkpoint written after updates gives the uninterrupted run's bytes
# (docs/input-impact.md "Checkpoints, restart and MPI ranks"):
#  1. DECK to T_END with a checkpoint every EVERY steps -> full/;
#  2. DECK to T_HALF (its last checkpoint after updates) -> half/; DECK to T_END --restart from
#     half's checkpoint -> cont/; --restart from full/'s last checkpoint -> last/;
#  3. impact_history.csv and impact_summary.csv but wall_time byte for byte, the final snapshot
#     by value (h5diff, no tolerance) equal to full/'s, and the checkpoints lie after updates
#     (ref_updates > 0) with the stored families (bond_vectors with SCOPE family);
#  4. RANKS > 1: the run under mpirun equals the serial one (replicated, docs/mpi.md), and its
#     checkpoint restarts on one rank to the same bytes.
# SED (optional) edits the deck's reference_update line first ("-": none).
# Usage: impact_merge_restart.sh MSCALE DECK T_END T_HALF EVERY SED [RANKS]
set -u
MSCALE=$1; DECK=$2; TEND=$3; THALF=$4; EVERY=$5; SED=$6; RANKS=${7:-1}
T=$(mktemp -d merge.XXXXXX); T=$PWD/$T
export OMP_NUM_THREADS=1 ASAN_OPTIONS="${ASAN_OPTIONS:-}:detect_leaks=0" # Open MPI's start-up leaks
if [[ "$SED" != "-" ]]; then sed "$SED" "$DECK" > "$T/deck.yaml"; else cp "$DECK" "$T/deck.yaml"; fi
grep -q "families: \(keep\|merge\)" "$T/deck.yaml" ||
  { echo "FAIL: the deck keeps no families (reference_update.families)"; exit 1; }
fail=0
run() { # DIR T_END [ARGS...]
  local d=$1 t=$2; shift 2
  "$MSCALE" run "$T/deck.yaml" -o "$T/$d" --quiet --set impact.t_end="$t" \
    --set impact.output.checkpoint_every="$EVERY" "$@" 2>> "$T/stderr" ||
    { cat "$T/stderr"; echo "FAIL: run $d"; exit 1; }
}
same() { # DIR_A DIR_B WHAT
  cmp -s "$1/impact_history.csv" "$2/impact_history.csv" ||
    { echo "FAIL: impact_history.csv differs ($3)"; fail=1; }
  cmp -s <(cut -d, -f5 --complement "$1/impact_summary.csv") \
    <(cut -d, -f5 --complement "$2/impact_summary.csv") ||
    { echo "FAIL: impact_summary.csv differs beyond wall_time ($3)"; fail=1; }
  local last
  last=$(ls "$1"/particles_[0-9]*.h5 | tail -1)
  h5diff -q "$last" "$2/$(basename "$last")" > /dev/null 2>&1 ||
    { echo "FAIL: $(basename "$last") differs ($3)"; fail=1; }
}
updates() { # the checkpoint's reference updates (an attribute of /impact/history)
  h5dump -a /impact/history/ref_updates "$1" | sed -n 's/^ *(0): *//p'
}
run full "$TEND"
run half "$THALF"
nu=$(updates "$T/half/impact_checkpoint.h5")
[[ -n "$nu" && "${nu%%.*}" -gt 0 ]] ||
  { echo "FAIL: the half run's checkpoint lies before any reference update ($nu)"; fail=1; }
if grep -q "scope: family" "$T/deck.yaml"; then
  h5ls "$T/half/impact_checkpoint.h5/impact/families" | grep -q bond_vectors ||
    { echo "FAIL: no per-family bond vectors in the checkpoint"; fail=1; }
fi
run cont "$TEND" --restart "$T/half/impact_checkpoint.h5"
same "$T/full" "$T/cont" "run to the end vs half run + restart after $nu updates"
run last "$TEND" --restart "$T/full/impact_checkpoint.h5"
same "$T/full" "$T/last" "run to the end vs restart from its last checkpoint"
if [[ "$RANKS" -gt 1 ]]; then
  launch=(mpirun --oversubscribe -np "$RANKS")
  [[ "$(id -u)" = 0 ]] && launch+=(--allow-run-as-root)
  "${launch[@]}" "$MSCALE" run "$T/deck.yaml" -o "$T/mpi" --quiet --set impact.t_end="$TEND" \
    --set impact.output.checkpoint_every="$EVERY" 2>> "$T/stderr" ||
    { cat "$T/stderr"; echo "FAIL: run on $RANKS ranks"; exit 1; }
  same "$T/full" "$T/mpi" "serial vs $RANKS ranks"
  "${launch[@]}" "$MSCALE" run "$T/deck.yaml" -o "$T/mpicont" --quiet --set impact.t_end="$TEND" \
    --set impact.output.checkpoint_every="$EVERY" --restart "$T/half/impact_checkpoint.h5" \
    2>> "$T/stderr" || { cat "$T/stderr"; echo "FAIL: restart on $RANKS ranks"; exit 1; }
  same "$T/full" "$T/mpicont" "serial vs $RANKS ranks restarted from the serial half run"
fi
[[ $fail -eq 0 ]] && rm -rf "$T" &&
  echo "impact_merge_restart: restarted after $nu reference updates to the uninterrupted run's bytes${RANKS:+ (ranks $RANKS)}"
exit $fail
