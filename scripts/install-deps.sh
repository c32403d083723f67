#!/usr/bin/env bash
# Installs every build and run dependency of demlab from Debian 12 packages.
# usage: scripts/install-deps.sh [--peer]   (--peer also installs LAMMPS for `demlab bench --peer`)
# Idempotent; needs root (or sudo). Nothing is downloaded outside Debian's archive.
set -euo pipefail
SUDO=""
if [ "$(id -u)" -ne 0 ]; then SUDO="sudo"; fi
PKGS=(
  build-essential cmake ninja-build pkg-config
  libeigen3-dev libbox2d-dev libcgal-dev libgmp-dev libmpfr-dev
  libosmesa6-dev libpng-dev libfreetype-dev fonts-dejavu-core
  libgtest-dev libtomlplusplus-dev libcli11-dev
  gnuplot-nox
  pybind11-dev python3-dev python3-numpy python3-pytest python3-matplotlib zlib1g-dev
  openmpi-bin libopenmpi-dev
  clang libclang-rt-14-dev
)
if [ "${1:-}" = "--peer" ]; then PKGS+=(lammps python3); fi
missing=()
for p in "${PKGS[@]}"; do
  dpkg-query -W -f='${Status}' "$p" 2>/dev/null | grep -q "install ok installed" || missing+=("$p")
done
if [ ${#missing[@]} -eq 0 ]; then
  echo "install-deps: all ${#PKGS[@]} packages present"
  exit 0
fi
echo "install-deps: installing ${missing[*]}"
export DEBIAN_FRONTEND=noninteractive
$SUDO apt-get update -qq
$SUDO apt-get install -y -qq --no-install-recommends "${missing[@]}" >/dev/null
echo "install-deps: done"
