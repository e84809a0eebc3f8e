#!/usr/bin/env bash
# SPDX-License-Identifier: MIT
# `cmake --install` into a temporary prefix; the installed binary, run from outside the source
# tree, runs shipped decks: one from PREFIX/share/mscale/inputs (its EOS table is
# ../eos/data/al_osa_cold.txt beside it), and copies of two decks in a folder of their own, whose
# data files (the EOS table, a piston history CSV) are found in the install's share directory.
#   test_install.sh BUILD_DIR SOURCE_DIR
set -u
build=$1 src=$2
tmp=$(mktemp -d)
trap 'rm -rf "$tmp"' EXIT
prefix=$tmp/prefix
fail=0
say_fail() { echo "FAIL: $*"; fail=1; }

cmake --install "$build" --prefix "$prefix" >"$tmp/install.log" 2>&1 ||
  { cat "$tmp/install.log"; echo "FAIL: cmake --install"; exit 1; }
share=$prefix/share/mscale
for f in bin/mscale share/doc/mscale/CHANGELOG.md share/mscale/inputs/default.yaml share/mscale/eos/data/al_osa_cold.txt \
         share/mscale/tools/plot_run.py share/doc/mscale/LICENSE share/doc/mscale/README.md \
         share/doc/mscale/developing.md; do
  [ -e "$prefix/$f" ] || say_fail "not installed: $f"
done
if [ -d "$src/python" ] && [ ! -d "$share/python" ]; then say_fail "python/ not installed"; fi
[ -x "$prefix/bin/mscale" ] || { echo "FAIL: no executable bin/mscale"; exit 1; }

# Outside the source tree, with no hint where the data is
cd "$tmp" || exit 1
unset MSCALE_DATA_DIR MSCALE_SOURCE_DIR
mscale=$prefix/bin/mscale
"$mscale" --version | head -1 | grep -qE '^mscale [0-9]+\.[0-9]+' || say_fail "mscale --version"
# CHANGELOG.md (Keep a Changelog) is installed and has a section for this version's release
project=$("$mscale" --version | head -1 | sed -nE 's/^mscale v?([0-9]+\.[0-9]+\.[0-9]+).*/\1/p')
log=$prefix/share/doc/mscale/CHANGELOG.md
grep -q '^## \[Unreleased\]' "$log" || say_fail "CHANGELOG.md: no '## [Unreleased]'"
grep -qF "## [$project]" "$log" || say_fail "CHANGELOG.md: no section '## [$project]'"

run() { # NAME DECK: run DECK into $tmp/NAME, expect exit 0 and run_info status completed
  if ! "$mscale" run "$2" -o "$tmp/$1" --quiet >"$tmp/$1.log" 2>&1; then
    cat "$tmp/$1.log"
    say_fail "$1: the installed mscale could not run $2"
    return
  fi
  grep -q '^status: completed' "$tmp/$1/run_info.yaml" || say_fail "$1: run_info status"
}
# eos-table-cold: a cold-curve table EOS read from a file (0.3 s)
run shipped "$share/inputs/eos-table-cold.yaml"
ls "$tmp/shipped"/*.csv >/dev/null 2>&1 || say_fail "shipped: no CSV written"
mkdir -p "$tmp/mine"
cp "$share/inputs/eos-table-cold.yaml" "$share/inputs/continuum-piston-file.yaml" "$tmp/mine/"
run copy-table "$tmp/mine/eos-table-cold.yaml"
run copy-history "$tmp/mine/continuum-piston-file.yaml"
# the same results as from the share directory: the same table was found
for f in "$tmp/shipped"/*.csv; do
  cmp -s "$f" "$tmp/copy-table/$(basename "$f")" || say_fail "copy-table: $(basename "$f") differs"
done
# a file that is nowhere is still an error at its deck position
sed 's#al_osa_cold.txt#no_such_table.txt#' "$share/inputs/eos-table-cold.yaml" >"$tmp/mine/bad.yaml"
"$mscale" check "$tmp/mine/bad.yaml" 2>"$tmp/bad.err"
rc=$?
[ "$rc" -eq 2 ] || say_fail "missing table: exit $rc, expected 2"
grep -q "bad.yaml:[0-9]*:[0-9]*: .*no_such_table.txt" "$tmp/bad.err" || say_fail "missing table: message"
[ "$fail" -eq 0 ] && echo "PASS: installed into $prefix; shipped and copied decks ran"
exit $fail
