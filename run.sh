#!/usr/bin/env bash
# SPDX-License-Identifier: MIT
# The main job: set up, build (Release), run the default deck, turn its outputs into plots.
#   ./run.sh [DECK] [OUTDIR]
set -euo pipefail
cd "$(dirname "$0")"
deck=${1:-inputs/default.yaml}
out=${2:-out/default}
./setup.sh
cmake -S . -B build -DCMAKE_BUILD_TYPE=Release
cmake --build build -j"$(nproc)"
build/mscale run "$deck" -o "$out" --force
if [[ -f tools/plot_run.py ]]; then
  /usr/bin/python3 tools/plot_run.py "$out"
fi
echo "outputs in $out"
