#!/usr/bin/env bash
# Bytes and seconds per written frame of the two time-series formats (docs/output.md):
# the reduced model on the coarse layer, OPEN_TRAIN_1 / jiggle_on_toes, 121 frames, body and layer series.
# Usage: scripts/measure_output.sh [OUT.md]   (default docs/results/output_formats.md; build first)
set -euo pipefail
cd "$(dirname "$0")/.."
sflsh=build/release/apps/sflsh/sflsh
report=${1:-docs/results/output_formats.md}
work=$(mktemp -d)
trap 'rm -rf "$work"' EXIT
frames=121
run() {  # name, options…
  local name=$1; shift
  "$sflsh" -q simulate --solver reduced --mesh coarse --subject OPEN_TRAIN_1 --motion jiggle_on_toes --frames $frames \
    --write-layer "$@" --out "$work/$name"
  /usr/bin/python3 - "$work/$name" "$name" "$frames" <<'PY'
import json, os, sys
folder, name, frames = sys.argv[1], sys.argv[2], int(sys.argv[3])
s = json.load(open(os.path.join(folder, "summary.json")))
size = sum(os.path.getsize(os.path.join(d, f)) for d, _, fs in os.walk(folder) for f in fs if f != "summary.json")
t = s["timings"]
print(f"| {name} | {size / 2**20:.1f} | {size / frames / 1024:.0f} | {1e3 * t['writer_seconds'] / frames:.1f} | "
      f"{1e3 * t['writer_wait_seconds'] / frames:.2f} | {1e3 * t['seconds_per_frame']:.1f} |")
PY
}
{
  echo "# Output formats: bytes and seconds per frame"
  echo
  echo "\`scripts/measure_output.sh\` on $(date -u +%Y-%m-%d), commit $(git rev-parse --short HEAD), $(nproc) cores: reduced model,"
  echo "coarse layer, OPEN_TRAIN_1, jiggle_on_toes, $frames frames, body and layer series (\`--write-layer\`). Writer time is"
  echo "the background writer's busy time; the wait is what the solver's thread waited for it (0: the writer keeps up)."
  echo
  echo "| format | MiB | KiB per frame | writer ms per frame | solver waited ms per frame | solve ms per frame |"
  echo "|---|---|---|---|---|---|"
  run "vtk (lz4)" --format vtk
  run "xdmf float64" --format xdmf
  run "xdmf float32" --format xdmf --precision float32
} > "$report"
cat "$report"
