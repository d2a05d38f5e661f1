#!/usr/bin/env bash
# The main job's sflsh commands (scripts/run_main_job.sh runs them after setup and build; the test
# tests/python/test_main_job.py runs them to check what they write): main_job_steps.sh SFLSH OUT.
# Poses the open body along a procedural motion, meshes the soft-tissue layer of the same subject, writes its
# material fields, and simulates its soft tissue with the full-space reference solver and with the reduced model;
# every time series is a compact XDMF + HDF5 series (docs/output.md).
set -euo pipefail
sflsh=${1:?usage: main_job_steps.sh SFLSH OUT}
out=${2:?usage: main_job_steps.sh SFLSH OUT}
data=$(cd "$(dirname "$0")/../data" && pwd)

# The posed body along the motion (4 s): body.xmf + body.h5 (`--format vtk` writes body.pvd of one .vtp per frame).
"$sflsh" motion export --motion jiggle_on_toes --subject OPEN_TRAIN_1 --format xdmf --out "$out"
# The soft-tissue layer (the template mesh is cached in ~/.cache/sflsh after the first run) and its material.
"$sflsh" mesh --subject OPEN_TRAIN_1 --thickness 0.5 --mesher cgal --mesh default --out "$out/layer"
# Its shape-dependent material: the shipped shape model (data/shape_models/default.toml, fitted on the coarse
# layer) evaluated at the subject's β — thickness and stiffness vary over the body and with its shape.
"$sflsh" material show --subject OPEN_TRAIN_1 --shape-model "$data/shape_models/default.toml" --mesh coarse \
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
