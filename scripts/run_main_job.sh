#!/usr/bin/env bash
# The main job on the embedded default data (no licensed data needed):
# installs the Debian packages, builds the sflsh executable (release; not the tests), and poses the open body along a
# procedural motion, writing a ParaView series to out/main_job/body.pvd; then meshes the soft-tissue
# layer of the same subject, writes its material fields, and simulates its soft tissue with the
# full-space reference solver and with the reduced model.
set -euo pipefail
cd "$(dirname "$0")/.."

scripts/setup.sh
cmake --preset release >/dev/null
cmake --build --preset release -j"$(nproc)" --target sflsh   # only what the main job runs; the tests build in command 2

out=${SFLSH_OUT:-out/main_job}
sflsh=build/release/apps/sflsh/sflsh
"$sflsh" motion export --motion jiggle_on_toes --subject OPEN_TRAIN_1 --out "$out"
# The soft-tissue layer (the template mesh is cached in ~/.cache/sflsh after the first run) and its material.
"$sflsh" mesh --subject OPEN_TRAIN_1 --thickness 0.5 --mesher cgal --mesh default --out "$out/layer"
# Its shape-dependent material: the shipped shape model (data/shape_models/default.toml, fitted on the coarse
# layer) evaluated at the subject's β — thickness and stiffness vary over the body and with its shape.
"$sflsh" material show --subject OPEN_TRAIN_1 --shape-model data/shape_models/default.toml --mesh coarse \
  --out "$out/material"
# The full-space reference solver on the same subject, motion and material (coarse layer, 2 s): soft tissue in motion.
"$sflsh" simulate --solver full --mesh coarse --subject OPEN_TRAIN_1 --motion jiggle_on_toes --frames 121 \
  --material "$out/material/material.toml" --write-layer --out "$out/fullspace"
# The reduced model (86 point handles + bone handles, cubature) on the same subject, motion, layer and material.
"$sflsh" simulate --solver reduced --mesh coarse --subject OPEN_TRAIN_1 --motion jiggle_on_toes --frames 121 \
  --material "$out/material/material.toml" --out "$out/reduced"
# A picture of the result: the posed body at its frame of largest soft-tissue motion, coloured by σ (mm).
"$sflsh" render --run "$out/fullspace" --out "$out/fullspace/picture.png"
"$sflsh" render --run "$out/reduced" --out "$out/reduced/picture.png"
echo "main job done: open $out/body.pvd, $out/layer/layer.vtu, $out/material/layer.vtu and"
echo "$out/fullspace/body.pvd (with $out/fullspace/layer.pvd and dynamics.vtp) and $out/reduced/body.pvd in ParaView;"
echo "pictures: $out/fullspace/picture.png and $out/reduced/picture.png"
