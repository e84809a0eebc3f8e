#!/bin/bash
# SPDX-License-Identifier: MIT
# Two builds of cd_lammps_bench side by side: problems A (400 steps) and B (600 steps), one
# thread pinned to core 1, old and new alternated so that drifts of the machine's load fall on
# both; prints every run and the medians of the process wall time and of its CPU time (user +
# system: on a loaded machine the wall time also counts the other processes' turns on the core,
# the CPU time does not) (docs/benchmarks.md).
#   bench/cd_lammps/ab_compare.sh OLD_BUILD_DIR NEW_BUILD_DIR [ROUNDS]
set -euo pipefail
old=$1/bench/cd_lammps/cd_lammps_bench new=$2/bench/cd_lammps/cd_lammps_bench rounds=${3:-6}
for b in "$old" "$new"; do [ -x "$b" ] || { echo "ab_compare.sh: no $b (build bench first)" >&2; exit 2; }; done
out=$(mktemp)
trap 'rm -f "$out"' EXIT
for ((r = 1; r <= rounds; r++)); do
  for prob in "A 400" "B 600"; do
    set -- $prob
    for which in old new; do
      bin=$old; [ $which = new ] && bin=$new
      s=$(date +%s.%N)
      cpu=$( { OMP_NUM_THREADS=1 /usr/bin/time -f '%U %S' taskset -c 1 "$bin" "$1" --steps "$2" \
        >/dev/null; } 2>&1 | tail -1 | awk '{printf "%.3f", $1 + $2}')
      e=$(date +%s.%N)
      printf '%d %s %s %.3f load %s cpu %s\n' "$r" "$1" "$which" "$(echo "$e - $s" | bc)" \
        "$(cut -d' ' -f1 /proc/loadavg)" "$cpu" | tee -a "$out"
    done
  done
done
for p in A B; do
  for which in old new; do
    awk -v p=$p -v w=$which '$2 == p && $3 == w {print $4}' "$out" | sort -n |
      awk -v p=$p -v w=$which '{a[NR] = $1} END {m = NR % 2 ? a[(NR + 1) / 2] : (a[NR / 2] + a[NR / 2 + 1]) / 2;
        printf "problem %s %s: median %.3f s over %d runs\n", p, w, m, NR}'
    awk -v p=$p -v w=$which '$2 == p && $3 == w {print $8}' "$out" | sort -n |
      awk -v p=$p -v w=$which '{a[NR] = $1} END {m = NR % 2 ? a[(NR + 1) / 2] : (a[NR / 2] + a[NR / 2 + 1]) / 2;
        printf "problem %s %s: median CPU time %.3f s over %d runs\n", p, w, m, NR}'
  done
done
