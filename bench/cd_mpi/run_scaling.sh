#!/bin/bash
# SPDX-License-Identifier: MIT
# Strong scaling 1 -> 2 ranks of cd_mpi_bench (docs/benchmarks.md): REPS interleaved rounds of
# {1 rank, 2 ranks auto (the decks' default), 2 ranks METIS, 2 ranks slab}; prints each run's
# SCALING line (and the per-rank lines of the 2-rank runs) and the medians:
# efficiency from the wall time T1/(2 T2) and from the CPU time outside MPI calls (the work of
# the slowest rank, which spinning in waits on a shared machine does not inflate).
#   bench/cd_mpi/run_scaling.sh BUILD_DIR [A|B] [STEPS] [REPS]
set -euo pipefail
bin=$1/bench/cd_mpi/cd_mpi_bench
prob=${2:-A} steps=${3:-1000} reps=${4:-3}
export OMP_NUM_THREADS=1
run() { mpirun --oversubscribe --allow-run-as-root -x OMP_NUM_THREADS -np "$1" "$bin" "$prob" \
          --steps "$steps" --partition "$2" | grep -E "SCALING|^rank|^decomp" | sed "s/^/$2 /"; }
out=$(for r in $(seq "$reps"); do
  echo "# round $r, load $(cut -d' ' -f1-3 /proc/loadavg)" >&2
  run 1 auto; run 2 auto; run 2 metis; run 2 slab
done)
echo "$out"
/usr/bin/python3 - "$out" <<'PY'
import sys, statistics as st
rows = [l.split() for l in sys.argv[1].splitlines() if "SCALING" in l]
def med(part, ranks, key):
    v = [float(r[r.index(key) + 1]) for r in rows if r[0] == part and r[3] == str(ranks)]
    return st.median(v) if v else float("nan")
t1w, t1c = med("auto", 1, "wall"), med("auto", 1, "cpu_work_max")
for part in ("auto", "metis", "slab"):
    t2w, t2c = med(part, 2, "wall"), med(part, 2, "cpu_work_max")
    print(f"{part}: T1 wall {t1w:.3f} s, T2 wall {t2w:.3f} s, efficiency {t1w / (2 * t2w):.3f}; "
          f"T1 cpu {t1c:.3f} s, T2 cpu (slowest rank, outside MPI) {t2c:.3f} s, "
          f"efficiency {t1c / (2 * t2c):.3f}")
PY
