#!/bin/bash
# SPDX-License-Identifier: MIT
# Checkpoints, interrupts and --continue of the `impact` problem (docs/reliability.md
# "Interrupts", docs/input-impact.md "Checkpoints, restart and MPI ranks"):
#  1. the deck runs to its end -> full/;
#  2. the same run -> cut/, SIGTERM once its first checkpoint of the cadence exists: it writes
#     a checkpoint at the top of its next step and stops, exit 1, `status: interrupted`, no .part
#     file, and its message offers `--continue` (not `--force`); that checkpoint must hold what
#     REQUIRE names (an attribute or dataset of it whose value or sum is > 0: `ref_updates`, the
#     families rebuilt on a moved reference; `/dm_fin/failed`, failed particles and broken bonds);
#  3. `mscale run DECK -o cut --continue` -> impact_history.csv byte for byte, every snapshot by
#     value (h5diff, no tolerance) and impact_summary.csv but its wall_time column equal to full/'s;
#  4. `--restart full/impact_checkpoint.h5` (the last of the cadence) -> the same;
#  5. the cadence output.checkpoint_time = t_end/4 (--set): 3 checkpoints, the same outputs, and
#     its last checkpoint continued by the deck as it is (checkpoint_every) -> the same;
#  6. a checkpoint refused (exit 2) by a different deck.
# RANKS > 1 runs every step under mpirun (SIGTERM to every rank, as a batch system sends it).
# Usage: impact_interrupt.sh MSCALE DECK RANKS REQUIRE
set -u
MSCALE=$1; DECK=$2; RANKS=$3; REQUIRE=$4
CKPT=impact_checkpoint.h5
T=$(mktemp -d impact_interrupt.XXXXXX); T=$PWD/$T
export OMP_NUM_THREADS=1 ASAN_OPTIONS="${ASAN_OPTIONS:-}:detect_leaks=0" # Open MPI's start-up leaks
launch=()
if [ "$RANKS" -gt 1 ]; then
  launch=(mpirun --oversubscribe -np "$RANKS")
  [ "$(id -u)" = 0 ] && launch+=(--allow-run-as-root)
fi
fail=0
same() { # DIR_A DIR_B WHAT: the outputs DIR_B has (at least the history and one snapshot)
  cmp -s "$1/impact_history.csv" "$2/impact_history.csv" ||
    { echo "FAIL: impact_history.csv differs ($3)"; fail=1; }
  cmp -s <(cut -d, -f5 --complement "$1/impact_summary.csv") \
    <(cut -d, -f5 --complement "$2/impact_summary.csv") ||
    { echo "FAIL: impact_summary.csv differs beyond wall_time ($3)"; fail=1; }
  local n=0
  for f in "$2"/particles_[0-9]*.h5; do
    [ -f "$f" ] || continue
    n=$((n + 1))
    h5diff -q "$1/$(basename "$f")" "$f" > /dev/null 2>&1 ||
      { echo "FAIL: $(basename "$f") differs ($3)"; fail=1; }
  done
  [ $n -gt 0 ] || { echo "FAIL: no snapshot in $2 ($3)"; fail=1; }
}
cp "$DECK" "$T/deck.yaml"
"${launch[@]}" "$MSCALE" run "$T/deck.yaml" -o "$T/full" --quiet 2>> "$T/stderr" ||
  { cat "$T/stderr"; echo "FAIL: full run"; exit 1; }

"${launch[@]}" "$MSCALE" run "$T/deck.yaml" -o "$T/cut" --quiet 2> "$T/cut.err" &
pid=$!
for i in $(seq 1 3000); do [ -f "$T/cut/$CKPT" ] && break; sleep 0.01; done
[ -f "$T/cut/$CKPT" ] || { echo "FAIL: no first checkpoint within 30 s"; kill -9 $pid; exit 1; }
if [ "$RANKS" -gt 1 ]; then pkill -TERM -P $pid; else kill -TERM $pid; fi
wait $pid; rc=$?
[ $rc = 1 ] || { echo "FAIL: the interrupted run exited $rc, not 1"; cat "$T/cut.err"; fail=1; }
grep -q "^status: interrupted" "$T/cut/run_info.yaml" ||
  { echo "FAIL: run_info.yaml does not say 'status: interrupted'"; fail=1; }
ls "$T/cut"/*.part > /dev/null 2>&1 && { echo "FAIL: .part files left"; fail=1; }
grep -q -- "-o $T/cut --continue. goes on" "$T/cut.err" ||
  { echo "FAIL: the message does not offer --continue"; cat "$T/cut.err"; fail=1; }
grep -q -- "--force" "$T/cut.err" && { echo "FAIL: the message offers --force"; fail=1; }
grep -o "interrupted; checkpoint at step [0-9]*" "$T/cut/run.log"
/usr/bin/python3 - "$T/cut/$CKPT" "$REQUIRE" << 'EOF' || fail=1
import sys, h5py, numpy as np
with h5py.File(sys.argv[1], "r") as f:
    what = sys.argv[2]
    v = f[what][()].sum() if what.startswith("/") else f["impact/history"].attrs[what]
    print(f"the interrupt's checkpoint: {what} = {v:g}")
    if not v > 0:
        sys.exit(f"FAIL: {what} is not > 0 in the interrupt's checkpoint: the test misses it")
EOF

"${launch[@]}" "$MSCALE" run "$T/deck.yaml" -o "$T/cut" --continue --quiet 2>> "$T/stderr" ||
  { cat "$T/stderr"; echo "FAIL: --continue"; exit 1; }
grep -q "^status: completed" "$T/cut/run_info.yaml" || { echo "FAIL: not completed"; fail=1; }
grep -o "restarted from .*" "$T/cut/run.log"
same "$T/full" "$T/cut" "uninterrupted vs interrupted + --continue"
cmp -s "$T/full/particles.xmf" "$T/cut/particles.xmf" ||
  { echo "FAIL: the snapshot series particles.xmf differs after --continue"; fail=1; }

"${launch[@]}" "$MSCALE" run "$T/deck.yaml" -o "$T/rs" --restart "$T/full/$CKPT" --quiet \
  2>> "$T/stderr" || { cat "$T/stderr"; echo "FAIL: --restart"; exit 1; }
grep -o "restarted from .*" "$T/rs/run.log"
same "$T/full" "$T/rs" "uninterrupted vs restart from its last checkpoint"

# the cadence in simulated time, output.checkpoint_time = t_end/4: checkpoints at the first
# steps past t_end/4, /2, 3/4; the same outputs (a checkpoint changes nothing of the run); its
# last checkpoint continued by the deck with the other cadence (left out of the deck's hash)
tq=$(sed -n 's/^  t_end: *\([0-9.e+-]*\).*/\1/p' "$T/deck.yaml" | awk '{print $1 / 4}')
"${launch[@]}" "$MSCALE" run "$T/deck.yaml" -o "$T/ct" --set impact.output.checkpoint_every=0 \
  --set "impact.output.checkpoint_time=$tq" --quiet 2>> "$T/stderr" ||
  { cat "$T/stderr"; echo "FAIL: checkpoint_time run"; exit 1; }
n=$(grep -c "checkpoint at step" "$T/ct/run.log")
[ "$n" = 3 ] || { echo "FAIL: $n checkpoints with checkpoint_time = t_end/4, not 3"; fail=1; }
same "$T/full" "$T/ct" "checkpoint_every vs checkpoint_time"
"${launch[@]}" "$MSCALE" run "$T/deck.yaml" -o "$T/rt" --restart "$T/ct/$CKPT" --quiet \
  2>> "$T/stderr" || { cat "$T/stderr"; echo "FAIL: --restart from checkpoint_time"; exit 1; }
grep -o "restarted from .*" "$T/rt/run.log"
same "$T/full" "$T/rt" "uninterrupted vs restart from a checkpoint_time checkpoint"

sed -e 's/spacing: \(.*\)/spacing: \1\n  courant: 0.39/' "$T/deck.yaml" > "$T/other.yaml"
"$MSCALE" run "$T/other.yaml" -o "$T/other" --restart "$T/full/$CKPT" --quiet 2> "$T/other.err"
rc=$?
[ $rc = 2 ] && grep -q "different deck" "$T/other.err" ||
  { echo "FAIL: a different deck's restart exited $rc"; cat "$T/other.err"; fail=1; }
[ $fail = 0 ] && echo "impact_interrupt: interrupted, checkpoint, --continue and --restart" \
  "identical to the uninterrupted run ($RANKS rank(s)); another deck refused" && rm -rf "$T"
exit $fail
