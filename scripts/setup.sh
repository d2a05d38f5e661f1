#!/usr/bin/env bash
# Installs every Debian package sflsh needs (Debian 12 "bookworm").
# Idempotent: when all packages are present it only checks dpkg and returns in about a second.
# Usage: scripts/setup.sh            (as root, or with sudo available)
set -euo pipefail

# VTK: Debian's libvtk9-dev and python3-vtk9, or, beside ParaView's Python (python3-paraview conflicts with
# python3-vtk9), the VTK that paraview-dev ships and the vtkmodules of python3-paraview. Chosen by
# SFLSH_PARAVIEW=1, or automatically when python3-paraview is already installed (docs/build.md).
vtk_packages=(libvtk9-dev python3-vtk9)
if [ "${SFLSH_PARAVIEW:-0}" = 1 ] ||
  dpkg-query -W -f='${Status}' python3-paraview 2>/dev/null | grep -q "install ok installed"; then
  vtk_packages=(paraview python3-paraview paraview-dev libfreetype-dev libglew-dev)  # the last two: targets ParaView's VTK config links
fi

packages=(
  build-essential cmake ninja-build pkg-config git
  libeigen3-dev libhdf5-dev petsc-dev libsundials-dev libcgal-dev libgmsh-dev gmsh
  "${vtk_packages[@]}"
  libcli11-dev nlohmann-json3-dev libtomlplusplus-dev libspdlog-dev libfmt-dev
  libzip-dev zlib1g-dev libtbb-dev libmuparser-dev
  googletest libgtest-dev libgmock-dev
  xvfb xauth clang-format
  python3-meshio
  python3-dev python3-numpy pybind11-dev python3-pybind11 pybind11-json-dev python3-pytest python3-matplotlib python3-h5py
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
