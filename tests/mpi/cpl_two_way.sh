#!/bin/bash
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
#   particle and ~1000 grid steps on 2 and 3 ranks: particles 1.8e-14 cm and 8.3e-12 km/s
#   (kinetic energy 8.9e-13), the grid's profiles 2.4e-10 of the column scale, its interface
#   history 6.4e-10, interface.csv 3.2e-11 (the interface velocity, a difference of nearly
#   equal node positions); fragment table and ejected mass equal to all printed digits. 1e-7
#   leaves 150x for round-off growing differently elsewhere; a lost ghost pair or a rank's
#   share of the interface force or of the drag returns lost shows at >= 1e-6 (a share is
#   O(1/P) of the whole);
# - what the gas received from the fragments (log, 6 digits) equal;
# - the transport arrivals to 1e-4 (as in cpl_cli.sh: CVODE turns round-off in its start state
#   into up to ~1e-6; measured equal to all 10 printed digits here).
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
echo "cpl_two_way: OK"
