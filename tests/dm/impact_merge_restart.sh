#!/bin/bash
# SPDX-License-Identifier: MIT
# A checkpoint taken after a reference update with merged families (impact.reference_update.
# families: merge) does not store those families, which the positions cannot rebuild
# (docs/particles-dm.md "Families kept or merged"): --continue must refuse it with a located
# message and exit 2, not continue on other families. Before any update it continues.
# With SCOPE = family the same for per-family references (reference_update.scope: family,
# docs/particles-dm.md "Per-family references"), whose families and vectors it does not store
# either.
# Usage: impact_merge_restart.sh MSCALE ROD_DECK [SCOPE]
set -u
MSCALE=$1; DECK=$2; SCOPE=${3:-}
T=$(mktemp -d merge.XXXXXX); T=$PWD/$T
export OMP_NUM_THREADS=1 ASAN_OPTIONS="${ASAN_OPTIONS:-}:detect_leaks=0"
EXTRA=""; [[ -n "$SCOPE" ]] && EXTRA=", scope: $SCOPE"
sed "s/reference_update: {threshold: 0.1}/reference_update: {threshold: 0.1, families: merge$EXTRA}/" \
  "$DECK" > "$T/rod.yaml"
grep -q "families: merge" "$T/rod.yaml" || { echo "FAIL: the deck has no reference_update line"; exit 1; }
fail=0
# to t = 1.5: checkpoints at steps 150 and 300, after reference updates (the first at step 127)
"$MSCALE" run "$T/rod.yaml" -o "$T/a" --quiet --set impact.t_end=1.5 || { echo "FAIL: run"; exit 1; }
"$MSCALE" run "$T/rod.yaml" -o "$T/a" --continue > "$T/a.log" 2>&1
rc=$?
if [[ $rc -ne 2 ]] || ! grep -q "checkpoint: the checkpoint lies after a reference update with impact.reference_update.families: merge" "$T/a.log"; then
  echo "FAIL: --continue after merged updates: exit $rc"; cat "$T/a.log"; fail=1
fi
# to t = 0.5 (before the first update, step 127): the checkpoint continues
"$MSCALE" run "$T/rod.yaml" -o "$T/b" --quiet --set impact.t_end=0.5 \
  --set impact.output.checkpoint_every=100 || { echo "FAIL: run b"; exit 1; }
"$MSCALE" run "$T/rod.yaml" -o "$T/b" --continue --quiet --set impact.t_end=1.0 \
  --set impact.output.checkpoint_every=100 || { echo "FAIL: --continue before any update"; fail=1; }
[[ $fail -eq 0 ]] && rm -rf "$T" && echo "impact_merge_restart: refused after merged updates, continued before"
exit $fail
