#!/bin/bash
# SPDX-License-Identifier: MIT
# `mscale run` of a two-way coupled deck (tests/mpi/data/cpl_two_way_mpi.yaml: grid up to the
# interface node, ~200 particles beyond it with a grooved free surface, a gas grid beyond that,
# fragments, drag returned to the gas, transport) serially and under mpirun -np 1, 2, 3
# (docs/mpi.md "The coupled problem on MPI ranks"). The grids are replicated; the particles'
# force on the interface node and the drag returns are summed over the ranks in rank order.
# - every rank count: the interface exchanges impulse exactly (grid + particles = 0 to 1e-12 of
#   it, round-off of ~1000 sums: measured 1e-15); on 2 and 3 ranks the run's own digest check
#   finds every rank's copy of the grids bitwise identical at the end;
# - against the serial run (compare_cpl_runs.py): spectra exact; interface.csv (interface
#   velocity, particle pressure, free-surface velocity, impulses, work), the grid's profiles
#   and interface history, ejected mass to 1e-7 of each column's scale, the fragment table to 1e-8;
#   the last snapshot's particles within 1e-10 cm and 1e-8 km/s. Why not equal: the ranks sum
#   the pair forces, hence the force on the piston layer, in another order; the grid receives
#   that round-off every grid step and hands it back through the piston. Measured after ~1100
#   particle and ~1000 grid steps on 2 and 3 ranks (METIS and auto partitions): particles
#   <= 1.3e-13 cm and 8.3e-12 km/s (kinetic energy 8.9e-13), the grid's profiles 2.4e-10 of the
#   column scale, its interface history 6.4e-10, interface.csv 6.5e-11 (the interface velocity,
#   a difference of nearly equal node positions); fragment table and ejected mass equal to all
#   printed digits. 1e-7
#   leaves 150x for round-off growing differently elsewhere; a lost ghost pair or a rank's
#   share of the interface force or of the drag returns lost shows at >= 1e-6 (a share is
#   O(1/P) of the whole);
# - what the gas received from the fragments (log, 6 digits) equal;
# - the transport arrivals to 1e-4 (as in cpl_cli.sh: CVODE turns round-off in its start state
#   into up to ~1e-6; measured <= 1e-10 here).
# Checkpoint/restart (below): byte-identical on the same rank count; the 2-rank checkpoint
# continued on 1 rank: measured particles 1.7e-16 cm, 3.9e-13 km/s, CSVs equal to the printed
# digits (asserted with the tolerances above).
# usage: cpl_two_way.sh MSCALE MPIEXEC DECK
source "$(dirname "$0")/cli_common.sh"
balance() { # the interface impulse balance of a run, relative to the particles' impulse
  sed -n 's/.*two-way interface balance.*impulse grid .* = .* (\(.*\) of it); work.*/\1/p' \
    "$1/run.log"
}
check_balance() {
  local b
  b=$(balance "$1")
  [ -n "$b" ] && /usr/bin/python3 -c "import sys; b = abs(float('$b')); print('$1: impulse balance', b); sys.exit(b >= 1e-12)" ||
    { echo "$1: impulse balance '$b' not within 1e-12"; exit 1; }
}
"$mscale" run "$deck" -o "$work/serial" --quiet
check_balance "$work/serial"
for np in 1 2 3; do
  mpirun $np "$mscale" run "$deck" -o "$work/np$np" --quiet
  grep -q "running .* on $np rank" "$work/np$np/run.log" ||
    { echo "np $np: no rank count in run.log"; exit 1; }
  if [ $np -gt 1 ]; then
    grep -q "replicated grid is bitwise identical on all $np ranks" "$work/np$np/run.log" ||
      { echo "np $np: no replicated-grid check in run.log"; exit 1; }
  fi
  check_balance "$work/np$np"
  # what the gas received from the fragments (drag kicks summed over the ranks, transport),
  # to the 6 printed digits: a rank's lost share would change it at O(1)
  gas() { sed -n 's/.*\(the gas received momentum .* kJ\) from the fragments.*/\1/p' "$1/run.log"; }
  [ -n "$(gas "$work/serial")" ] && [ "$(gas "$work/serial")" = "$(gas "$work/np$np")" ] ||
    { echo "np $np: gas return '$(gas "$work/np$np")' vs serial '$(gas "$work/serial")'"; exit 1; }
  /usr/bin/python3 "$(dirname "$0")/compare_cpl_runs.py" "$work/serial" "$work/np$np" \
    --dx 1e-10 --dv 1e-8 --tol 1e-7 \
    --csv interface.csv ejecta_mass.csv profile_0000.csv profile_final.csv history_interface.csv
done
# checkpoint/restart (docs/coupling.md §7b): checkpoints every 300 particle steps (at the end of
# the grid step that reaches them); restarted from the last one on the same rank count, every
# CSV file and the final snapshot must be byte-identical to the checkpointing run's (serially
# and on 2 ranks); the 2-rank checkpoint restarted on 1 rank agrees within the tolerances above
sed 's/^    outputs: 2/    outputs: 2\n    checkpoint_every: 300/' "$deck" > "$work/ckpt.yaml"
grep -q "checkpoint_every: 300" "$work/ckpt.yaml" || { echo "deck edit failed"; exit 1; }
for np in 1 2; do
  run() { if [ $np = 1 ]; then "$mscale" run "$@" --quiet; else mpirun $np "$mscale" run "$@" --quiet; fi; }
  run "$work/ckpt.yaml" -o "$work/ckA$np"
  run "$work/ckpt.yaml" -o "$work/ckB$np" --restart "$work/ckA$np/coupled_checkpoint.h5"
  grep -o "restarted from .* at particle step [0-9]*" "$work/ckB$np/run.log" ||
    { echo "np $np: no restart"; exit 1; }
  n=0
  for f in "$work/ckA$np"/*.csv; do
    cmp "$f" "$work/ckB$np/$(basename "$f")" ||
      { echo "restart on $np rank(s): $(basename "$f") differs"; exit 1; }
    n=$((n + 1))
  done
  h5diff -q "$work/ckA$np/particles_0002.h5" "$work/ckB$np/particles_0002.h5" ||
    { echo "restart on $np rank(s): the last snapshot differs"; exit 1; }
  echo "restart on $np rank(s): $n CSV files and the last snapshot byte-identical"
done
"$mscale" run "$work/ckpt.yaml" -o "$work/ckB1from2" --quiet --restart "$work/ckA2/coupled_checkpoint.h5"
/usr/bin/python3 "$(dirname "$0")/compare_cpl_runs.py" "$work/ckA2" "$work/ckB1from2" \
  --dx 1e-10 --dv 1e-8 --tol 1e-7 \
  --csv interface.csv ejecta_mass.csv profile_0000.csv profile_final.csv history_interface.csv
echo "cpl_two_way: OK"
