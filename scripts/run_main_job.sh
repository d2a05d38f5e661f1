#!/usr/bin/env bash
# The main job on the embedded default data (no licensed data needed):
# installs the Debian packages, builds sflsh (release), and poses the open body along a
# procedural motion, writing a ParaView series to out/main_job/body.pvd.
set -euo pipefail
cd "$(dirname "$0")/.."

scripts/setup.sh
cmake --preset release >/dev/null
cmake --build --preset release -j"$(nproc)"

out=${SFLSH_OUT:-out/main_job}
build/release/apps/sflsh/sflsh motion export --motion jiggle_on_toes --subject OPEN_TRAIN_1 --out "$out"
echo "main job done: open $out/body.pvd in ParaView (summary in $out/summary.json)"
