#!/usr/bin/env bash
# Runs every shipped scene (data/scenes/*.toml), draws a PNG strip of each (`sflsh render --strip 6`, offscreen)
# and tabulates what each summary.json reports: seconds per frame, the share of each effect, contact penetration,
# body exchanges, the free objects' energy balance and the tracking skeletons' deviation.
# Usage: scripts/scene_gallery.sh [OUT_DIR] [SCENE…]   (default docs/results/scenes, every scene; build first)
# The runs go to a temporary folder; OUT_DIR gets <scene>.png and scenes.md (the rows of scenes not named are kept).
set -euo pipefail
cd "$(dirname "$0")/.."
sflsh=build/release/apps/sflsh/sflsh
out=${1:-docs/results/scenes}
shift || true
scenes=("$@")
[ ${#scenes[@]} -gt 0 ] || scenes=(data/scenes/*.toml)
work=$(mktemp -d)
trap 'rm -rf "$work"' EXIT
mkdir -p "$out"
for scene in "${scenes[@]}"; do
  name=$(basename "$scene" .toml)
  echo "scene_gallery: $name" >&2
  if ! "$sflsh" -q simulate --scene "$scene" --out "$work/$name" 2> "$work/$name.log"; then
    echo "scene_gallery: $name failed: $(tail -1 "$work/$name.log")" >&2
    continue
  fi
  "$sflsh" -q render --run "$work/$name" --strip 6 --out "$out/$name.png" 2>> "$work/$name.log" ||
    echo "scene_gallery: $name: no strip ($(tail -1 "$work/$name.log"))" >&2
done
/usr/bin/python3 - "$work" "$out" "$(git rev-parse --short HEAD)" "$(nproc)" "${scenes[@]}" <<'PY'
import json, os, sys
work, out, commit, cores, scenes = sys.argv[1], sys.argv[2], sys.argv[3], sys.argv[4], sys.argv[5:]
rows, details = [], []
for scene in scenes:
    name = os.path.splitext(os.path.basename(scene))[0]
    path = os.path.join(work, name, "summary.json")
    if not os.path.exists(path):
        rows.append(f"| {name} | failed | | | | |")
        continue
    s = json.load(open(path))
    t = s["timings"]
    spf = 1.0 / t["frames_per_second"] if t.get("frames_per_second") else float("nan")
    effects = ", ".join(f"{e['name']} {100 * e['share']:.0f} %" for e in s["effects"] if e["share"] >= 0.005)
    pen = s.get("contact", {}).get("measured_max_penetration_mm")
    pen = f"{pen:.2f}" if isinstance(pen, (int, float)) else "–"
    sig = ", ".join(f"{b['name']} {b['dynamics']['sigma_max_mm']:.1f}" for b in s["bodies"] if "dynamics" in b)
    extra = []
    ex = s.get("body_exchange", {})
    if ex.get("contact_steps"):
        extra.append(f"body exchange: {ex['contact_steps']} touching steps, {ex['exchanges_mean']:.1f} exchanges "
                     f"(max {ex['exchanges_max']}), {ex['unconverged_steps']} unconverged, residual penetration "
                     f"{ex['residual_penetration_max_mm']:.2f} mm")
    for o in s.get("free_objects", []):
        e, c = o["energy"], o["contact"]
        extra.append(f"{o['name']}: energy {e['initial_J']:.3f} → {e['total_J']:.3f} J (max gain {e['max_gain_J']:.2g} J), "
                     f"penetration max {1e3 * c['max_penetration_m']:.2f} mm, last second {1e3 * c['last_second_max_penetration_m']:.2f} mm, "
                     f"push on it {c['max_body_force_N']:.0f} N vs body reaction {c['max_body_reaction_N']:.0f} N, "
                     f"final speed {sum(v * v for v in o['final_velocity_m_per_s']) ** 0.5:.3f} m/s")
    for b in s["bodies"]:
        k = b.get("skeleton")
        if isinstance(k, dict) and k.get("skeleton") == "tracking":
            text = (f"{b['name']} root: max {1e3 * k.get('max_root_displacement_m', 0):.1f} mm, "
                    f"{k.get('max_root_rotation_rad', 0):.3f} rad, final {1e3 * k.get('final_root_displacement_m', 0):.1f} mm")
            joints = sorted(k.get("joints", []), key=lambda j: -j["max_rotation_rad"])
            if joints:
                text += (f"; {len(joints)} joints, most bent " + ", ".join(
                    f"{j['joint']} {j['max_rotation_rad']:.3f} rad" for j in joints[:2]))
            extra.append(text)
    rows.append(f"| {name} | {1e3 * spf:.0f} | {effects} | {pen} | {sig} | {'; '.join(extra) or '–'} | {commit} |")
# Rows of scenes not run this time are kept from the existing table (each row says its commit).
path = os.path.join(out, "scenes.md")
run = {r.split("|")[1].strip() for r in rows}
if os.path.exists(path):
    for line in open(path):
        cells = line.split("|")
        if line.startswith("| ") and len(cells) == 9 and cells[1].strip() not in run and cells[1].strip() != "scene":
            rows.append(line.rstrip("\n"))
rows.sort(key=lambda r: r.split("|")[1].strip())
with open(path, "w") as f:
    f.write("# The shipped scenes: what each does and costs\n\n")
    f.write(f"`scripts/scene_gallery.sh` on {cores} cores, one run per scene at the commit in the last column (seconds vary with the "
            "machine's load). Seconds per frame: the scene loop (steps, penetration check, posing) over the frames; "
            "effects: share of the step time (summary.json → effects); penetration: the independent check of the "
            "skin against objects and other bodies (mm, tolerance 1 mm); σ_max per body (mm). Each scene's strip is "
            "`<scene>.png` beside this file: six evenly spaced frames, bodies coloured by soft-tissue displacement "
            "(mm).\n\n")
    f.write("| scene | ms per frame | effects | penetration [mm] | σ_max [mm] | contact, objects, skeleton | commit |\n")
    f.write("|---|---|---|---|---|---|---|\n")
    f.write("\n".join(rows) + "\n")
print(open(os.path.join(out, "scenes.md")).read())
PY
