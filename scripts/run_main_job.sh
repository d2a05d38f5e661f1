#!/usr/bin/env bash
# The main job on the embedded default data (no licensed data needed):
# installs the Debian packages, builds the sflsh executable (release; not the tests), and poses the open body along a
# procedural motion, writing a ParaView series to out/main_job/body.xmf; then meshes the soft-tissue
# layer of the same subject, writes its material fields, and simulates its soft tissue with the
# full-space reference solver and with the reduced model (scripts/main_job_steps.sh: the commands).
set -euo pipefail
cd "$(dirname "$0")/.."

scripts/setup.sh
cmake --preset release >/dev/null
cmake --build --preset release -j"$(nproc)" --target sflsh   # only what the main job runs; the tests build in command 2

out=${SFLSH_OUT:-out/main_job}
scripts/main_job_steps.sh build/release/apps/sflsh/sflsh "$out"
echo "main job done ($(du -sh "$out" | cut -f1) written): open $out/body.xmf, $out/layer/layer.vtu,"
echo "$out/material/layer.vtu, $out/fullspace/body.xmf (with $out/fullspace/layer.xmf and dynamics.vtp) and"
echo "$out/reduced/body.xmf in ParaView (XDMF reader) or meshio (docs/output.md);"
echo "pictures: $out/fullspace/picture.png and $out/reduced/picture.png"
