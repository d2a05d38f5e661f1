#!/usr/bin/env bash
# Installs every Debian package sflsh needs (Debian 12 "bookworm").
# Idempotent: when all packages are present it only checks dpkg and returns in about a second.
# Usage: scripts/setup.sh            (as root, or with sudo available)
set -euo pipefail

packages=(
  build-essential cmake ninja-build pkg-config git
  libeigen3-dev libhdf5-dev petsc-dev libsundials-dev libcgal-dev libgmsh-dev gmsh
  libvtk9-dev
  libcli11-dev nlohmann-json3-dev libtomlplusplus-dev libspdlog-dev libfmt-dev
  libzip-dev zlib1g-dev libtbb-dev libmuparser-dev
  googletest libgtest-dev libgmock-dev
  xvfb xauth clang-format
  python3-meshio
  python3-dev python3-numpy pybind11-dev python3-pybind11 pybind11-json-dev python3-pytest python3-matplotlib python3-h5py python3-vtk9
)

missing=()
for p in "${packages[@]}"; do
  if ! dpkg-query -W -f='${Status}' "$p" 2>/dev/null | grep -q "install ok installed"; then
    missing+=("$p")
  fi
done

if [ ${#missing[@]} -eq 0 ]; then
  echo "setup: all ${#packages[@]} packages present"
  exit 0
fi

echo "setup: installing ${#missing[@]} packages: ${missing[*]}"
SUDO=""
if [ "$(id -u)" -ne 0 ]; then SUDO="sudo"; fi
export DEBIAN_FRONTEND=noninteractive
$SUDO apt-get update -q
$SUDO apt-get install -y -q --no-install-recommends "${missing[@]}"
echo "setup: done"
