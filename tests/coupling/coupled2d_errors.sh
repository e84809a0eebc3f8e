#!/usr/bin/env bash
# SPDX-License-Identifier: MIT
# Deck errors of problem coupled2d (docs/input-coupled.md "coupled2d"): each broken copy of the
# shipped deck must be refused by `mscale check` with the expected message at FILE:LINE:COL,
# and the unbroken deck accepted.
# Usage: coupled2d_errors.sh MSCALE DECK
set -u
mscale=$1 deck=$2
dir=$(mktemp -d /tmp/mscale_coupled2d_errors_XXXXXX)
trap 'rm -rf "$dir"' EXIT
fail=0
"$mscale" check "$deck" > "$dir/ok.txt" 2>&1 || { echo "FAIL: the shipped deck is refused"; cat "$dir/ok.txt"; fail=1; }
# expect NAME SED-SCRIPT PATTERN: the sed-broken deck fails with PATTERN (a located message)
expect() {
  local name=$1 script=$2 pattern=$3 out="$dir/$1.txt"
  sed -e "$script" "$deck" > "$dir/$name.yaml"
  if "$mscale" check "$dir/$name.yaml" > "$out" 2>&1; then
    echo "FAIL $name: accepted"; fail=1; return
  fi
  if ! grep -Eq "^$dir/$name.yaml:[0-9]+:[0-9]+: .*$pattern" "$out"; then
    echo "FAIL $name: no located '$pattern' in:"; cat "$out"; fail=1; return
  fi
  echo "ok $name: $(grep -E "$pattern" "$out" | head -1)"
}
expect unknown_tag 's/^    tag: drive /    tag: drivex /' "drive.tag: no tag named 'drivex'"
expect unknown_fs_tag 's/free_surface_tag: free_surface/free_surface_tag: surf/' "no tag named 'surf'"
expect narrow 's/width: 3.0 /width: 2.0 /' "particles.width 2 cm does not fit the line 'drive'"
expect not_parallel 's/direction: \[0, -1\]/direction: [1, 0]/' "does not fit the line 'drive'"
expect not_flat 's/{name: free_surface, j: 0}/{name: free_surface, i: 0}/' "must be a node line parallel"
expect cluster 's/model: discrete_model/model: cluster_dynamics/' "no piston by columns"
expect bad_key 's/mirror: true /mirorr: true /' "mirorr"
expect late_t0 's/t0: 0.038 /t0: 0.09 /' "drive.t0 = 0.09 must be before the grid's time.end"
expect two_materials 's/{name: drive, j: 6}/{name: drive, j: 40}/' "must be one material"
exit $fail
