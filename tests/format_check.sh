#!/usr/bin/env bash
# SPDX-License-Identifier: MIT
# Fails if a tracked C file is not formatted as .clang-format says (docs/developing.md).
# Usage: tests/format_check.sh SOURCE_DIR
set -euo pipefail
cd "$1"
command -v clang-format >/dev/null || { echo "format_check: clang-format is not installed (setup.sh installs it)"; exit 1; }
mapfile -t files < <(git ls-files '*.c' '*.h' 2>/dev/null || find . -name '*.[ch]' -not -path './build*')
bad=$(clang-format --dry-run "${files[@]}" 2>&1 | grep -o '^[^:]*:[0-9]*:[0-9]*: warning' | cut -d: -f1 | sort -u || true)
if [[ -n $bad ]]; then
  echo "format_check: not formatted (run clang-format -i on them):"; echo "$bad"; exit 1
fi
echo "format_check: ${#files[@]} files formatted"
