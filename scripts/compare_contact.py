#!/usr/bin/python3
"""Compare the dent of two runs of one contact scene (docs/contact.md "Reduced against full space").

    scripts/compare_contact.py REFERENCE_RUN OTHER_RUN [--object NAME] [--json FILE]

Each run is an `sflsh simulate --scene` output folder written with VTK frames (`--format vtk`): the body's
`<body>_NNNNNN.vtp` and the objects' `objects_NNNNNN.vtp`. At the frame where the reference run's skin carries
the largest total contact force (the deepest press), both runs' skin vertices are binned by their distance to
the object's surface in the reference run (d = |p − c| − r for the object's bounding sphere: exact for a ball):
`dent_mm` is the mean |soft_tissue_displacement| within 10 cm, `spread_mm` the mean 10–20 cm away. The largest
contact force is summary.json's (bodies[0].contact.objects.max_force_n). Prints one table row per run and the
ratios other / reference.
"""
import argparse
import glob
import json
import os
import sys

import numpy as np
import vtk
from vtk.util.numpy_support import vtk_to_numpy


def read(path):
    reader = vtk.vtkXMLPolyDataReader()
    reader.SetFileName(path)
    reader.Update()
    data = reader.GetOutput()
    if data.GetNumberOfPoints() == 0:
        sys.exit(f"{path}: no points (expected a VTK PolyData frame)")
    return data


def array(data, name):
    a = data.GetPointData().GetArray(name)
    if a is None:
        sys.exit(f"a frame has no point array '{name}' (write the runs with the default or 'all' fields)")
    return vtk_to_numpy(a)


def body_frames(run):
    summary = json.load(open(os.path.join(run, "summary.json")))
    body = summary["bodies"][0]["name"]
    frames = sorted(glob.glob(os.path.join(run, f"{body}_[0-9]*.vtp")))
    if not frames:
        sys.exit(f"{run}: no {body}_NNNNNN.vtp frames (run with --format vtk and without --no-output)")
    return summary, frames


def main():
    parser = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    parser.add_argument("reference")
    parser.add_argument("other")
    parser.add_argument("--json", help="write the figures here")
    args = parser.parse_args()
    ref_summary, ref_frames = body_frames(args.reference)
    other_summary, other_frames = body_frames(args.other)
    if len(ref_frames) != len(other_frames):
        sys.exit(f"the runs have {len(ref_frames)} and {len(other_frames)} frames")
    # The deepest frame: the largest total contact force on the reference skin [N].
    totals = [np.linalg.norm(array(read(f), "contact_force").sum(axis=0)) for f in ref_frames]
    k = int(np.argmax(totals))
    name = os.path.basename(ref_frames[k])
    number = name.rsplit("_", 1)[1]
    objects = read(os.path.join(args.reference, f"objects_{number}"))
    points = vtk_to_numpy(objects.GetPoints().GetData())
    centre = points.mean(axis=0)
    radius = np.linalg.norm(points - centre, axis=1).max()
    ref = read(ref_frames[k])
    distance = np.linalg.norm(vtk_to_numpy(ref.GetPoints().GetData()) - centre, axis=1) - radius
    near, far = distance < 0.10, (distance >= 0.10) & (distance < 0.20)
    rows = {}
    for label, run, summary, frames in (("reference", args.reference, ref_summary, ref_frames),
                                        ("other", args.other, other_summary, other_frames)):
        u = np.linalg.norm(array(read(frames[k]), "soft_tissue_displacement"), axis=1) * 1000.0
        contact = summary["bodies"][0].get("contact", {}).get("objects", {})
        rows[label] = {"run": run, "max_force_n": contact.get("max_force_n", 0.0), "dent_mm": float(u[near].mean()),
                       "spread_mm": float(u[far].mean()), "solve_seconds": summary["bodies"][0].get("solve_seconds")}
    ratios = {key: rows["other"][key] / rows["reference"][key] for key in ("max_force_n", "dent_mm", "spread_mm")
              if rows["reference"][key] > 0}
    print(f"frame {k} (t = {k / ref_summary['scene']['fps']:.3f} s), {near.sum()} vertices within 10 cm, "
          f"{far.sum()} at 10-20 cm")
    print(f"{'run':<40} {'max force [N]':>14} {'dent [mm]':>10} {'spread [mm]':>12}")
    for r in rows.values():
        print(f"{r['run'][-40:]:<40} {r['max_force_n']:14.2f} {r['dent_mm']:10.2f} {r['spread_mm']:12.2f}")
    print("ratio other / reference: " + ", ".join(f"{key} {value:.2f}" for key, value in ratios.items()))
    if args.json:
        json.dump({"frame": k, "rows": rows, "ratios": ratios}, open(args.json, "w"), indent=1)


if __name__ == "__main__":
    main()
