#!/bin/bash
# SPDX-License-Identifier: MIT
# Time mscale's cluster dynamics against LAMMPS on problems A and B of
# bench/problems/cd_lammps.md, alternating the two codes in one session (docs/benchmarks.md).
#   bench/cd_lammps/run_compare.sh BUILD_DIR LAMMPS_DIR [REPS] [CASES] [THREADS]
# THREADS: a list of N (mscale with N OpenMP threads against LAMMPS on N ranks) and Nr (mscale
# on N MPI ranks, bench/cd_mpi's cd_mpi_bench with its default partition, against LAMMPS on N).
# LAMMPS_DIR: a writable copy of bench/problems/lammps where gen/ was made by
# `/usr/bin/python3 gen_inputs.py gen` (run.sh does it). Prints one markdown row per run pair:
# loop times, particle-steps/s and the ratio, with the 1-minute load average before each pair;
# then the CPU seconds of the loop (LAMMPS: loop time × its "% CPU use" × ranks; mscale: process
# CPU time, all threads) and the ratio of particle-steps per CPU-second, the fairer figure when
# other processes share the cores.
set -u
BENCH=$1/bench/cd_lammps/cd_lammps_bench
MPIBENCH=$1/bench/cd_mpi/cd_mpi_bench
LMPDIR=$2
REPS=${3:-2}
CASES=${4:-"A B"}
THREADS=${5:-"1 2"}
declare -A NP=([A]=256000 [B]=320000) STEPS=([A]=1000 [B]=2000) INP=([A]=in.bulk [B]=in.piston)
cp "$LMPDIR"/in.bulk "$LMPDIR"/in.piston "$LMPDIR"/gen/ 2>/dev/null
echo "| rep | problem | ranks/threads | load (1 min) | LAMMPS loop s | mscale loop s | LAMMPS p-steps/s | mscale p-steps/s | ratio | LAMMPS CPU s | mscale CPU s | CPU ratio |"
echo "|---|---|---|---|---|---|---|---|---|---|---|---|"
for rep in $(seq 1 "$REPS"); do
  for c in $CASES; do
    for nt in $THREADS; do
      load=$(cut -d' ' -f1 /proc/loadavg)
      np=${nt%r}
      log=$(mktemp)
      (cd "$LMPDIR/gen" && OMP_NUM_THREADS=1 mpirun --allow-run-as-root --oversubscribe -np "$np" \
         lmp -in "${INP[$c]}" -log "$log" -screen none > /dev/null 2>&1)
      tl=$(awk '/^Loop time of/{print $4}' "$log")
      cl=$(awk -v nt="$np" -v tl="$tl" '/% CPU use with/{sub("%", "", $1); print tl * $1 / 100 * nt}' "$log")
      rm -f "$log"
      if [[ $nt == *r ]]; then
        out=$(OMP_NUM_THREADS=1 mpirun --allow-run-as-root --oversubscribe -x OMP_NUM_THREADS -np "$np" \
                "$MPIBENCH" "$c" --steps "${STEPS[$c]}")
        tm=$(echo "$out" | awk '/^SCALING/{print $5}')
        cm=$(echo "$out" | awk '/^SCALING/{print $9}')
      else
        out=$(OMP_NUM_THREADS=$nt OMP_PROC_BIND=true "$BENCH" "$c")
        tm=$(echo "$out" | awk '/^loop time/{print $3}')
        cm=$(echo "$out" | awk '/^process CPU time/{print $7}')
      fi
      n=${NP[$c]}; s=${STEPS[$c]}
      awk -v r="$rep" -v c="$c" -v nt="$nt" -v ld="$load" -v tl="$tl" -v tm="$tm" -v n="$n" -v s="$s" \
        -v cl="$cl" -v cm="$cm" \
        'BEGIN{pl=n*s/tl; pm=n*s/tm; printf "| %d | %s | %s | %s | %.2f | %.2f | %.3g | %.3g | %.2f | %.2f | %.2f | %.2f |\n", r, c, nt, ld, tl, tm, pl, pm, pm/pl, cl, cm, cl/cm}'
    done
  done
done
