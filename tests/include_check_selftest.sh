#!/usr/bin/env bash
# SPDX-License-Identifier: MIT
# include_check.py must catch a violation: a copy of the library folders in which the coupled
# problem includes cluster dynamics' header (and, separately, continuum's private one).
set -euo pipefail
src=$1
tmp=$(mktemp -d)
trap 'rm -rf "$tmp"' EXIT
for bad in cd.h cont_run.h; do
  rm -rf "$tmp/tree"
  mkdir -p "$tmp/tree"
  (cd "$src" && tar cf - --exclude='*.txt' --exclude='data' core eos continuum particles coupling app) | tar xf - -C "$tmp/tree"
  sed -i "0,/#include \"coupled_impl.h\"/s//#include \"coupled_impl.h\"\n#include \"$bad\"/" \
    "$tmp/tree/coupling/coupled.c"
  if python3 "$src/tests/include_check.py" "$tmp/tree" >"$tmp/out" 2>&1; then
    echo "include_check_selftest: a coupled.c including $bad was not caught"; exit 1
  fi
  grep -q "coupling/coupled.c" "$tmp/out" || { cat "$tmp/out"; exit 1; }
done
python3 "$src/tests/include_check.py" "$src" >/dev/null
echo "include_check_selftest: both violations caught, the tree itself is clean"
