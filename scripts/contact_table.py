#!/usr/bin/python3
"""The table of docs/contact.md "Reduced against full space": each contact scene run with the full-space model,
the reduced model and the reduced model without local resolution (the handles alone), everything else as in the
scene file; the largest contact force, the dent and its spread from summary.json, and the solve time.

    scripts/contact_table.py [--sflsh PATH] [--out DIR] SCENE.toml …

Prints a Markdown table and writes DIR/contact_table.json. Free objects: the last column gives the object's final
height along gravity [mm] (where it rests).
"""
import argparse
import json
import os
import re
import subprocess
import sys


def variant(scene_text, solver, local):
    text = re.sub(r'(?m)^solver\s*=\s*"[a-z]+"', f'solver = "{solver}"', scene_text)
    if not re.search(r'(?m)^solver\s*=', text):
        text = re.sub(r'(?m)^\[\[body\]\]\s*$', f'[[body]]\nsolver = "{solver}"', text, count=1)
    if not local:
        if re.search(r'(?m)^\[contact\]\s*$', text):
            text = re.sub(r'(?m)^\[contact\]\s*$', '[contact]\nlocal_resolution = false', text, count=1)
        else:
            text = re.sub(r'(?m)^\[\[body\]\]', '[contact]\nlocal_resolution = false\n\n[[body]]', text, count=1)
    return text


def main():
    parser = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    parser.add_argument("scenes", nargs="+")
    parser.add_argument("--sflsh", default="build/release/apps/sflsh/sflsh")
    parser.add_argument("--out", default="runs/contact_table")
    args = parser.parse_args()
    os.makedirs(args.out, exist_ok=True)
    results = []
    for scene in args.scenes:
        name = os.path.splitext(os.path.basename(scene))[0]
        text = open(scene).read()
        row = {"scene": name}
        for label, solver, local in (("full", "full", True), ("reduced", "reduced", True),
                                     ("handles", "reduced", False)):
            path = os.path.join(args.out, f"{name}_{label}.toml")
            open(path, "w").write(variant(text, solver, local))
            out = os.path.join(args.out, f"{name}_{label}")
            run = subprocess.run([args.sflsh, "simulate", "--scene", path, "--out", out, "--no-output"],
                                 capture_output=True, text=True)
            if run.returncode != 0:
                row[label] = {"error": run.stderr.strip().splitlines()[-1] if run.stderr.strip() else "failed"}
                continue
            summary = json.load(open(os.path.join(out, "summary.json")))
            body = summary["bodies"][0]
            objects = body.get("contact", {}).get("objects", {})
            entry = {"max_force_n": objects.get("max_force_n", 0.0), "dent_mm": objects.get("dent_mm"),
                     "spread_mm": objects.get("spread_mm"), "solve_seconds": body["solve_seconds"],
                     "steps": body["steps"], "newton_iterations": body["newton_iterations"], "model": body["model"]}
            for o in summary.get("objects", []):
                if o.get("motion") == "free" and "final_position" in o:
                    entry["free_final_position"] = o["final_position"]
            row[label] = entry
        results.append(row)
        print(json.dumps(row), file=sys.stderr)
    json.dump(results, open(os.path.join(args.out, "contact_table.json"), "w"), indent=1)

    def cell(r, key, fmt="{:.2f}"):
        v = r.get(key)
        return fmt.format(v) if isinstance(v, (int, float)) else "–"

    print("| scene | model | max force [N] | dent ≤ 10 cm [mm] | spread 10–20 cm [mm] | force / full | dent / full "
          "| spread / full | solve [ms/step] |")
    print("|---|---|---|---|---|---|---|---|---|")
    for row in results:
        full = row.get("full", {})
        for label in ("full", "reduced", "handles"):
            r = row.get(label, {})
            if "error" in r:
                print(f"| {row['scene']} | {label} | failed: {r['error'][:80]} | | | | | | |")
                continue
            ratios = []
            for key in ("max_force_n", "dent_mm", "spread_mm"):
                a, b = r.get(key), full.get(key)
                ratios.append(f"{a / b:.2f}" if isinstance(a, (int, float)) and isinstance(b, (int, float)) and b
                              else "–")
            per_step = 1000.0 * r["solve_seconds"] / max(1, r["steps"])
            print(f"| {row['scene']} | {label} | {cell(r, 'max_force_n')} | {cell(r, 'dent_mm')} | "
                  f"{cell(r, 'spread_mm')} | {' | '.join(ratios)} | {per_step:.1f} |")


if __name__ == "__main__":
    main()
