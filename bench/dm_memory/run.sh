#!/bin/bash
# SPDX-License-Identifier: MIT
# Memory per particle of the discrete model (docs/benchmarks.md): the peak resident set of
# `mscale run` on bench/dm_memory/dm_memory.yaml at two lengths in x, for response
# linear_elastic and eos (elastic_plastic, so the deviator is live); bytes per particle = the
# difference of the peaks over the difference of the particle counts (the fixed cost of the
# process and the libraries cancels).
# usage: bench/dm_memory/run.sh [MSCALE]   (default build/mscale; about 1 min on one core)
set -euo pipefail
here=$(cd "$(dirname "$0")" && pwd)
mscale=${1:-build/mscale}
work=$(mktemp -d)
trap 'rm -rf "$work"' EXIT
export OMP_NUM_THREADS=1
peak() { # RESPONSE NX -> peak RSS in kB
  local layer="{material: al, response: $1}"
  [ "$1" == eos ] && layer="{material: al, response: eos, yield: elastic_plastic, yield_stress: 0.29}"
  sed -e "s|{material: al, response: linear_elastic}|$layer|" \
      -e "s|hi: \[0.4, 0.4, 0.4\]|hi: [$(echo "$2 * 0.01" | bc -l), 0.4, 0.4]|" \
      "$here/dm_memory.yaml" > "$work/deck.yaml"
  /usr/bin/time -f %M "$mscale" run "$work/deck.yaml" -o "$work/out" --force --quiet \
    2>&1 >/dev/null | tail -1
}
n1=$((40 * 40 * 40)) n2=$((120 * 40 * 40))
for resp in linear_elastic eos; do
  a=$(peak $resp 40) b=$(peak $resp 120)
  echo "$resp: peak RSS $a kB ($n1 particles), $b kB ($n2 particles): $(echo "($b - $a) * 1024 / ($n2 - $n1)" | bc) B per particle"
done
