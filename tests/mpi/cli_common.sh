# SPDX-License-Identifier: MIT
# Sourced by the `mscale run` MPI tests (tests/mpi/*.sh, arguments MSCALE MPIEXEC DECK): strict
# mode, the arguments, a scratch directory removed on exit, one OpenMP thread per rank (the
# ranks share 2 cores), and `mpirun NP CMD...` (oversubscribed; --allow-run-as-root is
# harmless when not root).
set -euo pipefail
mscale=$1 mpiexec=$2 deck=$3
work=$(mktemp -d)
trap 'rm -rf "$work"' EXIT
export OMP_NUM_THREADS=1
mpirun() { "$mpiexec" --oversubscribe --allow-run-as-root -np "$@"; }
