#!/usr/bin/env bash
# Checks that sflsh builds, passes its tests and opens in pvpython on a Debian 12 machine that has ParaView with
# its Python (python3-paraview, which conflicts with the python3-vtk9 that libvtk9-dev depends on).
# It bootstraps a clean Debian 12 into a folder (debootstrap), installs the dependencies there with
# `SFLSH_PARAVIEW=1 scripts/setup.sh`, builds a clone of this checkout against ParaView's VTK, runs the tests and
# lets pvpython read a run folder. Needs root and the Debian mirror; takes about 40 min on 2 cores.
# Usage: sudo scripts/check_paraview_build.sh [ROOT_FOLDER]      (default /var/tmp/sflsh-paraview-root)
# The folder is kept for reuse (a second run skips the bootstrap and the packages already there).
set -euo pipefail
cd "$(dirname "$0")/.."
root=${1:-/var/tmp/sflsh-paraview-root}
[ "$(id -u)" -eq 0 ] || { echo "check_paraview_build: run as root (debootstrap, chroot)"; exit 1; }
command -v debootstrap >/dev/null || apt-get install -y -q --no-install-recommends debootstrap

if [ ! -x "$root/usr/bin/apt-get" ]; then
  debootstrap --variant=minbase bookworm "$root" http://deb.debian.org/debian
fi
cp /etc/resolv.conf "$root/etc/"
cleanup() { umount "$root/proc" "$root/sys" "$root/dev" 2>/dev/null || true; }
trap cleanup EXIT
mountpoint -q "$root/proc" || mount -t proc proc "$root/proc"
mountpoint -q "$root/dev" || mount --bind /dev "$root/dev"
# MPI (hwloc) reads the CPU topology from sysfs and prints a warning on every start without it.
mountpoint -q "$root/sys" || mount -t sysfs sysfs "$root/sys"

rm -rf "$root/src/sflsh"
mkdir -p "$root/src"
git clone -q . "$root/src/sflsh"

chroot "$root" /bin/bash -euo pipefail -c '
  apt-get update -q
  apt-get install -y -q --no-install-recommends ca-certificates git
  cd /src/sflsh
  SFLSH_PARAVIEW=1 scripts/setup.sh
  dpkg-query -W -f="\${Status}" python3-paraview | grep -q "install ok installed"
  if dpkg-query -W -f="\${Status}" libvtk9-dev 2>/dev/null | grep -q "install ok installed"; then
    echo "check_paraview_build: libvtk9-dev is installed beside python3-paraview"; exit 1
  fi
  cmake --preset release -DSFLSH_WERROR=ON | grep "VTK "
  cmake --build --preset release -j"$(nproc)"
  ctest --preset release -j"$(nproc)"
  # The main job, then pvpython reads what it wrote.
  build/release/apps/sflsh/sflsh -q simulate --subject OPEN_TRAIN_1 --motion jiggle_on_toes --frames 12 \
    --format vtk --out /tmp/pv-run
  pvpython -c "
from paraview.simple import OpenDataFile, UpdatePipeline
reader = OpenDataFile(\"/tmp/pv-run/body.pvd\")
UpdatePipeline()
info = reader.GetDataInformation()
assert info.GetNumberOfPoints() > 0, \"no points\"
print(\"check_paraview_build: pvpython read body.pvd,\", info.GetNumberOfPoints(), \"points\")
"
'
echo "check_paraview_build: sflsh builds, passes its tests and opens in pvpython beside python3-paraview"
