#!/usr/bin/env bash
# Bytes and seconds per written frame of the two time-series formats (docs/output.md):
# the reduced model on the coarse layer, OPEN_TRAIN_1 / jiggle_on_toes, 121 frames, body and layer series.
# Each format runs RUNS times (default 3); the table gives the medians of the timings.
# Usage: scripts/measure_output.sh [OUT.md]   (default docs/results/output_formats.md; build first)
set -euo pipefail
cd "$(dirname "$0")/.."
sflsh=build/release/apps/sflsh/sflsh
report=${1:-docs/results/output_formats.md}
runs=${RUNS:-3}
work=$(mktemp -d)
trap 'rm -rf "$work"' EXIT
frames=121
run() {  # name, options…
  local name=$1; shift
  for k in $(seq "$runs"); do
    rm -rf "$work/$k"
    "$sflsh" -q simulate --solver reduced --mesh coarse --subject OPEN_TRAIN_1 --motion jiggle_on_toes \
      --frames $frames --write-layer "$@" --out "$work/$k"
  done
  /usr/bin/python3 - "$work" "$name" "$frames" "$runs" <<'PY'
import json, os, statistics, sys
work, name, frames, runs = sys.argv[1], sys.argv[2], int(sys.argv[3]), int(sys.argv[4])
sizes, writer, wait, solve = [], [], [], []
for k in range(1, runs + 1):
    folder = os.path.join(work, str(k))
    s = json.load(open(os.path.join(folder, "summary.json")))
    sizes.append(sum(os.path.getsize(os.path.join(d, f)) for d, _, fs in os.walk(folder) for f in fs
                     if f != "summary.json"))
    t = s["timings"]
    writer.append(t["writer_seconds"]); wait.append(t["writer_wait_seconds"]); solve.append(t["seconds_per_frame"])
m = statistics.median
size = m(sizes)
print(f"| {name} | {size / 2**20:.1f} | {size / frames / 1024:.0f} | {1e3 * m(writer) / frames:.1f} | "
      f"{1e3 * m(wait) / frames:.2f} | {1e3 * m(solve):.1f} |")
PY
}
{
  echo "# Output formats: bytes and seconds per frame"
  echo
  echo "\`scripts/measure_output.sh\` on $(date -u +%Y-%m-%d), commit $(git rev-parse --short HEAD), $(nproc) cores, load"
  echo "$(cut -d' ' -f1 /proc/loadavg) at the start; medians of $runs runs per format: reduced model, coarse layer, OPEN_TRAIN_1,"
  echo "jiggle_on_toes, $frames frames, body and layer series (\`--write-layer\`). VTK frames carry their arrays inline"
  echo "(base64 binary, docs/decisions.md). Writer time is the background writer's busy time; the wait is what the"
  echo "solver's thread waited for it (0: the writer keeps up)."
  echo
  echo "| format | MiB | KiB per frame | writer ms per frame | solver waited ms per frame | solve ms per frame |"
  echo "|---|---|---|---|---|---|"
  run "vtk (lz4, every array)" --format vtk
  run "xdmf float64, every array, uncompressed" --format xdmf --precision float64 --fields all --compression none
  run "xdmf float32, every array, uncompressed" --format xdmf --precision float32 --fields all --compression none
  run "xdmf default (float32, display arrays, zlib)" --format xdmf
} > "$report"
cat "$report"
