#!/usr/bin/env bash
# SPDX-License-Identifier: MIT
# The whole test suite: set up, build (Release), run every ctest test (unit, validation, mpi),
# then rebuild with AddressSanitizer + UndefinedBehaviorSanitizer and run the unit tests again.
#   ./test.sh            everything (what CI runs)
#   ./test.sh --quick    Release unit tests only
set -euo pipefail
cd "$(dirname "$0")"
./setup.sh
jobs=$(nproc)
cmake -S . -B build -DCMAKE_BUILD_TYPE=Release
cmake --build build -j"$jobs"
if [[ ${1:-} == --quick ]]; then
  ctest --test-dir build -L unit --output-on-failure -j"$jobs"
  exit 0
fi
ctest --test-dir build --output-on-failure -j"$jobs"
echo "== sanitizer build (ASan + UBSan): unit tests"
cmake -S . -B build-asan -DCMAKE_BUILD_TYPE=Debug -DMSCALE_SANITIZE=ON
cmake --build build-asan -j"$jobs"
ASAN_OPTIONS=detect_leaks=1:abort_on_error=1 LSAN_OPTIONS=suppressions=$PWD/tests/lsan.supp \
  UBSAN_OPTIONS=print_stacktrace=1:halt_on_error=1 \
  ctest --test-dir build-asan -L unit --output-on-failure -j"$jobs"
