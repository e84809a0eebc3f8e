#!/bin/sh
# SPDX-License-Identifier: MIT
# Run one libFuzzer harness at low priority, one process, for a fixed time (docs/reliability.md).
# FUZZ_TIMEOUT (s, default 10): per-input limit; libFuzzer measures wall time, so on a loaded
# machine at nice 19 raise it (60) or starved inputs are reported as hangs.
#   fuzz/run.sh BUILD_DIR HARNESS SECONDS [WORKDIR]
# Corpus:   WORKDIR/corpus/HARNESS  (seeded on first use from inputs/, eos/data and the bad-input
#           corpus tests/reliability/bad/ and bad/data/), crashes in WORKDIR/artifacts/, log in WORKDIR/HARNESS.log.
# Scratch files go to /dev/shm (tmpfs) when it exists; the eos/data tables and the corpus's
# bad/data files are copied there so decks naming them by relative path reach the readers.
set -eu
build=$1 harness=$2 seconds=$3 work=${4:-/tmp/mscale-fuzz}
src=$(cd "$(dirname "$0")/.." && pwd)
bin="$build/fuzz/$harness"
[ -x "$bin" ] || { echo "no $bin: configure with -DMSCALE_FUZZ=ON (see fuzz/CMakeLists.txt)" >&2; exit 2; }
corpus="$work/corpus/$harness"
mkdir -p "$corpus" "$work/artifacts"
scratch=/dev/shm/mscale-fuzz-scratch
[ -d /dev/shm ] || scratch="$work/scratch"
mkdir -p "$scratch"
cp "$src"/eos/data/* "$src"/inputs/*.csv "$scratch"/ 2>/dev/null || true
mkdir -p "$scratch/data"
cp "$src"/tests/reliability/bad/data/* "$scratch/data"/
if [ -z "$(ls -A "$corpus")" ]; then
  case $harness in
    fuzz_deck|fuzz_app_deck)
      cp "$src"/inputs/*.yaml "$corpus"/
      cp "$src"/tests/reliability/bad/*.yaml "$corpus"/ 2>/dev/null || true ;;
    fuzz_table)
      for f in "$src"/eos/data/*.txt "$src"/tests/reliability/bad/data/*.csv \
               "$src"/tests/reliability/bad/data/*.txt; do
        [ -f "$f" ] && { printf '\003'; cat "$f"; } > "$corpus/$(basename "$f")"
      done ;;
    fuzz_eos_table)
      for f in "$src"/eos/data/*.txt "$src"/tests/reliability/bad/data/*.txt; do
        [ -f "$f" ] || continue
        { printf '\000'; cat "$f"; } > "$corpus/cold-$(basename "$f")"
        { printf '\001'; cat "$f"; } > "$corpus/full-$(basename "$f")"
      done ;;
    fuzz_h5_raw)
      cp "$src"/tests/reliability/bad/data/*.h5 "$corpus"/ 2>/dev/null || true ;;
  esac
fi
dict=
case $harness in fuzz_deck|fuzz_app_deck) dict="-dict=$src/fuzz/yaml.dict" ;; esac
TMPDIR=$scratch nice -n 19 "$bin" $dict -max_total_time="$seconds" -timeout="${FUZZ_TIMEOUT:-10}" -rss_limit_mb=2048 \
  -max_len="${FUZZ_MAX_LEN:-2048}" ${FUZZ_EXTRA:-} \
  -malloc_limit_mb=1024 -artifact_prefix="$work/artifacts/$harness-" -print_final_stats=1 \
  "$corpus" > "$work/$harness.log" 2>&1 || true
grep -E "stat::number_of_executed_units|stat::average_exec_per_sec|ERROR|SUMMARY|Test unit written" \
  "$work/$harness.log" | sed "s/^/$harness: /"
