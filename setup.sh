#!/usr/bin/env bash
# SPDX-License-Identifier: MIT
# Installs what mscale needs on a bare Debian 12 (run as root, or with sudo available).
# Every dependency is a Debian package; nothing is downloaded from anywhere else.
set -euo pipefail
packages=(
  gcc make cmake pkg-config clang-format   # toolchain; clang-format: the format test
  libopenmpi-dev openmpi-bin           # MPI
  libhdf5-openmpi-dev hdf5-tools       # parallel HDF5 (snapshots, tables), h5dump
  libsundials-dev                      # KINSOL (Hugoniot), CVODE (ejecta transport)
  libmetis-dev                         # partitioning
  libyaml-dev                          # input decks
  libcmocka-dev                        # unit tests
  python3 python3-numpy python3-h5py python3-matplotlib   # post-processing and plots
  python3-yaml                         # tests/app read run_info.yaml and the resolved deck
  python3-pandas                       # python/mscale: Table.to_pandas (optional; tested)
  python3-ase                          # the export test reads extended XYZ back with ASE
  paraview python3-paraview            # pvpython: the test that ParaView opens our XDMF series
)
missing=()
for p in "${packages[@]}"; do
  dpkg-query -W -f='${Status}' "$p" 2>/dev/null | grep -q "install ok installed" || missing+=("$p")
done
if ((${#missing[@]})); then
  echo "setup: installing ${missing[*]}"
  SUDO=""
  [[ $(id -u) -ne 0 ]] && SUDO=sudo
  $SUDO apt-get update -qq
  DEBIAN_FRONTEND=noninteractive $SUDO apt-get install -y -qq --no-install-recommends "${missing[@]}"
else
  echo "setup: all Debian packages present"
fi
