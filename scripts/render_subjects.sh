#!/usr/bin/env bash
# Pictures of the bodies (PNG, offscreen VTK under a virtual X server):
#   scripts/render_subjects.sh [OUT_DIR] [SUBJECTS] [extra `sflsh body render` options…]
# SUBJECTS: comma-separated names, or all | open | paper (default: open).
# Example: scripts/render_subjects.sh renders/jump open --motion one_leg_jump --time 1.2
set -euo pipefail
cd "$(dirname "$0")/.."
out=${1:-renders}
subjects=${2:-open}
shift $(( $# > 2 ? 2 : $# ))
sflsh=build/release/apps/sflsh/sflsh
[ -x "$sflsh" ] || { echo "render_subjects: build first (cmake --preset release && cmake --build --preset release)" >&2; exit 1; }
command -v xvfb-run >/dev/null || { echo "render_subjects: xvfb-run missing; run scripts/setup.sh" >&2; exit 1; }
xvfb-run -a -s "-screen 0 1920x1080x24" "$sflsh" body render --subjects "$subjects" --views front,side --out "$out" "$@"
