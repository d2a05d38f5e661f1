#!/usr/bin/env python3
"""Record a fixed set of runs and show that a change left every number in them unchanged.

A restructuring of the code (docs/architecture.md) must not change what users get. This script runs the same
set of commands with two builds and compares everything they wrote:

    scripts/same_results.py record --sflsh OLD/sflsh --python OLD_PYDIR --out /tmp/before
    scripts/same_results.py record --sflsh build/release/apps/sflsh/sflsh --python build/release/python --out /tmp/after
    scripts/same_results.py compare /tmp/before /tmp/after

The runs: `simulate` in full space and with the reduced model, a contact scene (belly_press), `tradeoff --preset
quick`, `validate --preset quick` and the Python example (examples/python_jiggle.py), all on the coarse layer with a
shared mesh cache. `compare` reads every summary.json (numbers at every key except wall-clock timings and the like),
every .csv (numeric cells), every .h5 dataset (the XDMF frames) and every .vtp / .vtu array (the VTK frames), and
prints the largest relative difference per file; it exits 1 when one exceeds --rtol (default 1e-12, the bound for a
change that moves only the order of a sum). Files present on one side only are reported as differences too.

About 10 minutes on 2 cores per `record` (validate's quick preset is most of it).
"""
import argparse
import csv
import json
import math
import os
import re
import subprocess
import sys
import time

# Keys whose values depend on the machine, the moment, the folder or the cache, not on the results (`pareto`:
# whether a tradeoff row is on the accuracy-time front, and an effect's `share` of the time, depend on measured times).
IGNORED_KEY = re.compile(
    r"(^argv$|^cache$|^share$|pareto|utc|second|wall|_ms$|_ms_|fps|per_s$|rate|rss|memory|bytes|date|host|version|"
    r"git|command|cwd|path|file|"
    r"folder|dir$|threads|processes|started|finished|elapsed|speed|cost)",
    re.IGNORECASE)


def runs(sflsh, out, cache):
    common = []  # the cache comes from SFLSH_CACHE
    return [
        ("simulate_full", [sflsh, "simulate", "--solver", "full", "--mesh", "coarse", "--frames", "24",
                           "--motion", "jiggle_on_toes", "--subject", "OPEN_TRAIN_5", "--out", os.path.join(out, "simulate_full")] + common),
        ("simulate_reduced", [sflsh, "simulate", "--solver", "reduced", "--mesh", "coarse", "--frames", "90",
                              "--motion", "shake_hips", "--subject", "OPEN_TEST_2", "--energies",
                              "--out", os.path.join(out, "simulate_reduced")] + common),
        ("scene_belly_press", [sflsh, "simulate", "--scene", "data/scenes/belly_press.toml",
                               "--out", os.path.join(out, "scene_belly_press")] + common),
        ("tradeoff_quick", [sflsh, "tradeoff", "--preset", "quick", "--out", os.path.join(out, "tradeoff_quick")]
         + common),
        ("validate_quick", [sflsh, "validate", "--preset", "quick", "--out", os.path.join(out, "validate_quick")]
         + common),
    ]


def record(args):
    os.makedirs(args.out, exist_ok=False)
    cache = os.path.abspath(args.cache or os.path.join(args.out, "cache"))
    log = {}
    for name, cmd in runs(os.path.abspath(args.sflsh), os.path.abspath(args.out), cache):
        if args.only and name not in args.only:
            continue
        t0 = time.time()
        result = subprocess.run(cmd, capture_output=True, text=True, env=dict(os.environ, SFLSH_CACHE=cache))
        log[name] = {"command": cmd, "exit": result.returncode, "seconds": time.time() - t0}
        print(f"{name}: exit {result.returncode} in {time.time() - t0:.0f} s", flush=True)
        if result.returncode != 0:
            print(result.stderr[-2000:], file=sys.stderr)
    if not args.only or "python_example" in args.only:
        env = dict(os.environ, PYTHONPATH=os.path.abspath(args.python))
        target = os.path.join(os.path.abspath(args.out), "python_example", "jiggle.png")
        os.makedirs(os.path.dirname(target))
        cmd = [sys.executable, "examples/python_jiggle.py", "--out", target, "--frames", "60", "--cache", cache]
        t0 = time.time()
        result = subprocess.run(cmd, capture_output=True, text=True, env=env)
        log["python_example"] = {"command": cmd, "exit": result.returncode, "seconds": time.time() - t0}
        print(f"python_example: exit {result.returncode} in {time.time() - t0:.0f} s", flush=True)
        if result.returncode != 0:
            print(result.stderr[-2000:], file=sys.stderr)
    with open(os.path.join(args.out, "runs.json"), "w") as f:
        json.dump(log, f, indent=1)
    return 0 if all(r["exit"] == 0 for r in log.values()) else 1


def rel(a, b):
    if a == b or (isinstance(a, float) and isinstance(b, float) and math.isnan(a) and math.isnan(b)):
        return 0.0
    scale = max(abs(a), abs(b))
    return abs(a - b) / scale if scale > 0 else 0.0


def only_ignored(value):
    """Whether a JSON table holds nothing but ignored keys (at any depth)."""
    if not isinstance(value, dict):
        return False
    return all(IGNORED_KEY.search(k) or only_ignored(v) for k, v in value.items())


def json_diff(a, b, key=""):
    """Largest relative difference over the numeric leaves of two JSON values, and the key where it is."""
    if isinstance(a, dict) and isinstance(b, dict):
        worst = (0.0, "")
        for k in set(a) | set(b):
            if IGNORED_KEY.search(k):
                continue
            if k not in a or k not in b:
                if only_ignored(a.get(k, b.get(k))):
                    continue  # e.g. a "timings" table that one side gained: nothing in it is a result
                return (math.inf, f"{key}.{k} (on one side only)")
            worst = max(worst, json_diff(a[k], b[k], f"{key}.{k}"))
        return worst
    if isinstance(a, list) and isinstance(b, list):
        if len(a) != len(b):
            return (math.inf, f"{key} (lengths {len(a)} and {len(b)})")
        worst = (0.0, "")
        for i, (x, y) in enumerate(zip(a, b)):
            worst = max(worst, json_diff(x, y, f"{key}[{i}]"))
        return worst
    if isinstance(a, bool) or isinstance(b, bool) or isinstance(a, str) or isinstance(b, str):
        return (0.0, "") if a == b else (math.inf, f"{key} ({a!r} against {b!r})")
    if isinstance(a, (int, float)) and isinstance(b, (int, float)):
        return (rel(float(a), float(b)), key)
    return (0.0, "") if a == b else (math.inf, f"{key} ({a!r} against {b!r})")


def csv_diff(pa, pb):
    with open(pa) as fa, open(pb) as fb:
        ra, rb = list(csv.reader(fa)), list(csv.reader(fb))
    if len(ra) != len(rb):
        return (math.inf, f"rows {len(ra)} and {len(rb)}")
    header = ra[0] if ra else []
    worst = (0.0, "")
    for i, (x, y) in enumerate(zip(ra, rb)):
        if len(x) != len(y):
            return (math.inf, f"row {i} has {len(x)} and {len(y)} cells")
        for j, (u, v) in enumerate(zip(x, y)):
            column = header[j] if j < len(header) else str(j)
            if IGNORED_KEY.search(column):
                continue
            try:
                worst = max(worst, (rel(float(u), float(v)), f"row {i} {column}"))
            except ValueError:
                if u != v:
                    return (math.inf, f"row {i} {column} ({u!r} against {v!r})")
    return worst


def array_diff(x, y, name):
    import numpy as np
    x, y = np.asarray(x, dtype=float), np.asarray(y, dtype=float)
    if x.shape != y.shape:
        return (math.inf, f"{name} shapes {x.shape} and {y.shape}")
    if x.size == 0:
        return (0.0, name)
    scale = max(float(np.nanmax(np.abs(x))), float(np.nanmax(np.abs(y))), 1e-300)
    same_nan = np.array_equal(np.isnan(x), np.isnan(y))
    if not same_nan:
        return (math.inf, f"{name} NaN pattern")
    d = np.nan_to_num(np.abs(x - y))
    return (float(d.max()) / scale, name)


def h5_diff(pa, pb):
    import h5py
    worst = (0.0, "")
    with h5py.File(pa, "r") as fa, h5py.File(pb, "r") as fb:
        names_a, names_b = [], []
        fa.visititems(lambda n, o: names_a.append(n) if isinstance(o, h5py.Dataset) else None)
        fb.visititems(lambda n, o: names_b.append(n) if isinstance(o, h5py.Dataset) else None)
        if sorted(names_a) != sorted(names_b):
            return (math.inf, "different datasets")
        for n in names_a:
            worst = max(worst, array_diff(fa[n][()], fb[n][()], n))
    return worst


def vtk_diff(pa, pb):
    import vtk
    from vtk.util.numpy_support import vtk_to_numpy
    reader = vtk.vtkXMLPolyDataReader if pa.endswith(".vtp") else vtk.vtkXMLUnstructuredGridReader

    def read(p):
        r = reader()
        r.SetFileName(p)
        r.Update()
        d = r.GetOutput()
        arrays = {"points": vtk_to_numpy(d.GetPoints().GetData()) if d.GetPoints() else None}
        for kind, data in (("point", d.GetPointData()), ("cell", d.GetCellData())):
            for i in range(data.GetNumberOfArrays()):
                arrays[f"{kind}/{data.GetArrayName(i)}"] = vtk_to_numpy(data.GetArray(i))
        return arrays

    a, b = read(pa), read(pb)
    if sorted(a) != sorted(b):
        return (math.inf, "different arrays")
    worst = (0.0, "")
    for n in a:
        if a[n] is not None:
            worst = max(worst, array_diff(a[n], b[n], n))
    return worst


def compare(args):
    failures, checked = 0, 0
    files_a, files_b = set(), set()
    for root, _, names in os.walk(args.a):
        files_a |= {os.path.relpath(os.path.join(root, n), args.a) for n in names}
    for root, _, names in os.walk(args.b):
        files_b |= {os.path.relpath(os.path.join(root, n), args.b) for n in names}
    skip = lambda p: p.startswith("cache") or p == "runs.json" or p.endswith((".png", ".log", ".txt", ".md", ".xmf",
                                                                             ".pvd", ".svg", ".lock"))
    for p in sorted((files_a ^ files_b)):
        if not skip(p):
            print(f"DIFFERENT  {p}: on one side only")
            failures += 1
    for p in sorted(files_a & files_b):
        if skip(p):
            continue
        pa, pb = os.path.join(args.a, p), os.path.join(args.b, p)
        if p.endswith(".json"):
            with open(pa) as fa, open(pb) as fb:
                d = json_diff(json.load(fa), json.load(fb))
        elif p.endswith(".csv"):
            d = csv_diff(pa, pb)
        elif p.endswith(".h5"):
            d = h5_diff(pa, pb)
        elif p.endswith((".vtp", ".vtu")):
            d = vtk_diff(pa, pb)
        else:
            continue
        checked += 1
        bad = not d[0] <= args.rtol
        failures += bad
        if bad or args.verbose:
            print(f"{'DIFFERENT' if bad else 'same     '}  {p}: largest relative difference {d[0]:.3g} at {d[1]}")
    print(f"{checked} files compared, {failures} differ beyond {args.rtol:g}")
    return 1 if failures else 0


def main():
    parser = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    sub = parser.add_subparsers(dest="command", required=True)
    r = sub.add_parser("record", help="run the fixed set of commands into a folder")
    r.add_argument("--sflsh", default="build/release/apps/sflsh/sflsh")
    r.add_argument("--python", default="build/release/python", help="folder of the sflsh Python module")
    r.add_argument("--out", required=True)
    r.add_argument("--cache", help="mesh cache (default OUT/cache; share one between records to save time)")
    r.add_argument("--only", nargs="*", help="run only these (names as printed)")
    c = sub.add_parser("compare", help="compare two recorded folders")
    c.add_argument("a")
    c.add_argument("b")
    c.add_argument("--rtol", type=float, default=1e-12)
    c.add_argument("--verbose", action="store_true")
    args = parser.parse_args()
    return record(args) if args.command == "record" else compare(args)


if __name__ == "__main__":
    sys.exit(main())
