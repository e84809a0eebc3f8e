#!/bin/sh
# SPDX-License-Identifier: MIT
# Valgrind memcheck of every `unit`-labelled test (docs/reliability.md §6).
#   tools/valgrind_unit.sh [BUILD_DIR [CTEST_ARGS...]]    default BUILD_DIR: build-valgrind
# Builds without -march=native (valgrind does not know every AVX-512 instruction) and with
# debug info, runs each test executable through valgrind (CMAKE_CROSSCOMPILING_EMULATOR: ctest
# puts the emulator in front of every test whose command is a target) and the bad-input cases'
# `mscale` through it (MSCALE_TEST_WRAPPER, read by tests/reliability/run_bad_case.sh).
# A memory error or a definite/indirect leak makes valgrind exit 1, which fails the test.
# Suppressions (tools/valgrind.supp) cover third-party start-up code only, each one explained.
set -eu
src=$(cd "$(dirname "$0")/.." && pwd)
build=${1:-$src/build-valgrind}
[ $# -gt 0 ] && shift
vg="valgrind;--error-exitcode=1;--leak-check=full;--errors-for-leak-kinds=definite,indirect"
vg="$vg;--show-leak-kinds=definite,indirect;--track-origins=yes;--num-callers=30"
vg="$vg;--suppressions=$src/tools/valgrind.supp;--quiet"
cmake -S "$src" -B "$build" -DCMAKE_BUILD_TYPE=RelWithDebInfo -DMSCALE_NATIVE=OFF \
  -DMSCALE_SANITIZE=OFF "-DCMAKE_CROSSCOMPILING_EMULATOR=$vg" > "$build.configure.log"
cmake --build "$build" -j2 > "$build.build.log"
# Under valgrind a test runs 20-50x slower: lift the per-test time limits of the generated files.
find "$build" -name CTestTestfile.cmake -exec sed -i 's/TIMEOUT "[0-9.]*"/TIMEOUT "3600"/g' {} +
MSCALE_TEST_WRAPPER=$(printf '%s' "$vg" | tr ';' ' ')
# One OpenMP thread: valgrind serialises threads anyway, and libgomp's pool adds nothing.
export MSCALE_TEST_WRAPPER OMP_NUM_THREADS=1
start=$(date +%s)
status=0
ctest --test-dir "$build" -L unit --output-on-failure "$@" || status=$?
echo "valgrind_unit: $(($(date +%s) - start)) s wall, ctest exit $status"
exit $status
