#!/usr/bin/env python3
"""Soak: the crowd scene for ten minutes of simulated time, every frame written (CTest `soak.crowd`, label `long`).

Runs `sflsh simulate --scene` on the shipped crowd scene's settings (dancing avatars with random shapes, reduced
solver, coarse mesh) for `--minutes` of simulated time at the scene's 30 fps, sampling the process's resident memory
and the frames written so far once a second, then checks:
  - the run exits 0 and its summary.json is complete (every avatar, every frame, finite σ);
  - resident memory is flat after the first simulated minute (see FLAT_MB below);
  - every frame file is readable by VTK's own reader, with the requested array, finite, on every point, at its time.
The memory curve goes to <work>/rss.csv (wall s, simulated s, frames, RSS MB) and a table of it to stdout.

Fewer avatars than the shipped 25 and one point array per frame keep the output on disk small (36,001 frames of 2
avatars × ~0.4 MB ≈ 15 GB: the whole crowd with every array would be ~700 GB); the per-frame work of each avatar, the
writer thread, the pvd series and the summary are the same code as the full crowd's.
"""
import argparse
import csv
import json
import math
import os
import shutil
import subprocess
import sys
import time
from pathlib import Path

import numpy as np
from vtkmodules.util.numpy_support import vtk_to_numpy
from vtkmodules.vtkIOXML import vtkXMLPolyDataReader

# Resident memory may rise by at most this much after the first simulated minute. What grows by design is the .pvd
# series' list of its files (written at the end): measured ~250 bytes per frame file, 9 MB over the nine minutes of
# two avatars, and ~6 MB for the summary at the end. A leak of one 7,000-vertex float64 array per frame (~170 KB)
# would add 6 GB, and one of 1 KB per frame file 32 MB more, which is what this bound still catches.
FLAT_MB = 32.0

SCENE = """# Soak scene written by tests/soak/crowd_soak.py: the crowd of data/scenes/crowd.toml, fewer avatars, longer
[scene]
name = "soak"
fps = {fps}
duration = {duration}

[effects]
inertia = true

[output]
fields = ["soft_tissue_displacement"]
format = "vtk"

[crowd]
count = {count}
seed = 7
shape_sigma = 1.0
motion = "dance"
max_offset = 2.0
spacing = 1.6
columns = {count}
solver = "reduced"
mesh = "coarse"
handles = 30
"""


def rss_mb(pid):
    try:
        with open(f"/proc/{pid}/status") as status:
            for line in status:
                if line.startswith("VmRSS:"):
                    return int(line.split()[1]) / 1024.0
    except OSError:
        pass
    return None


def frames_written(parent, name, first_avatar):
    """Frames of the first avatar written so far, counted in the run's staging folder (core/run_folder.hpp)."""
    count = 0
    for staging in parent.glob(f".{name}.staging-*"):
        try:
            count = max(count, sum(1 for f in os.scandir(staging) if f.name.startswith(first_avatar + "_") and f.name[len(first_avatar) + 1].isdigit()))
        except OSError:
            pass
    return count


def check_frame(path, array, time_expected, fps):
    reader = vtkXMLPolyDataReader()
    reader.SetFileName(str(path))
    reader.Update()
    data = reader.GetOutput()
    points = data.GetNumberOfPoints()
    if reader.GetErrorCode() != 0 or points == 0:
        return f"{path}: unreadable (VTK error {reader.GetErrorCode()}, {points} points)"
    values = data.GetPointData().GetArray(array)
    if values is None:
        return f"{path}: no point array '{array}'"
    values = vtk_to_numpy(values)
    if values.shape[0] != points or not np.all(np.isfinite(values)):
        return f"{path}: '{array}' has {values.shape[0]} rows for {points} points or a non-finite value"
    times = data.GetFieldData().GetArray("TimeValue")
    if times is None or abs(times.GetValue(0) - time_expected) > 0.5 / fps:
        return f"{path}: TimeValue {None if times is None else times.GetValue(0)} against {time_expected}"
    return None


def main():
    parser = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    parser.add_argument("--sflsh", required=True)
    parser.add_argument("--cache", required=True)
    parser.add_argument("--work", required=True, help="scratch folder (emptied first; the frames are deleted at the end)")
    parser.add_argument("--minutes", type=float, default=10.0, help="simulated minutes")
    parser.add_argument("--count", type=int, default=2, help="avatars")
    parser.add_argument("--fps", type=int, default=30)
    parser.add_argument("--threads", type=int, default=2)
    parser.add_argument("--keep", action="store_true", help="keep the frames")
    args = parser.parse_args()

    work = Path(args.work)
    shutil.rmtree(work, ignore_errors=True)
    work.mkdir(parents=True)
    duration = args.minutes * 60.0
    (work / "soak.toml").write_text(SCENE.format(fps=args.fps, duration=duration, count=args.count))
    out = work / "run"
    command = [args.sflsh, "-q", "simulate", "--scene", str(work / "soak.toml"), "--out", str(out), "--cache",
               args.cache, "--threads", str(args.threads), "--allow-long"]
    print(" ".join(command), flush=True)
    start = time.monotonic()
    with open(work / "stderr.txt", "w") as err:
        process = subprocess.Popen(command, stdout=subprocess.DEVNULL, stderr=err)
        samples = []
        while process.poll() is None:
            rss = rss_mb(process.pid)
            if rss is not None:
                frames = frames_written(work, "run", "avatar_00")
                samples.append((time.monotonic() - start, frames / args.fps, frames, rss))
            time.sleep(1.0)
    wall = time.monotonic() - start
    with open(work / "rss.csv", "w", newline="") as f:
        writer = csv.writer(f)
        writer.writerow(["wall_s", "simulated_s", "frames", "rss_mb"])
        writer.writerows(samples)
    failures = []
    if process.returncode != 0:
        print((work / "stderr.txt").read_text(), file=sys.stderr)
        print(f"sflsh exited {process.returncode} after {wall:.0f} s", file=sys.stderr)
        return 1

    # The memory curve, one row per simulated minute, and the flatness check after the first minute.
    print(f"{wall:.0f} s wall for {duration:.0f} s simulated, {args.count} avatars; resident memory:")
    print("| simulated min | wall s | RSS MB |\n|---|---|---|")
    for minute in range(int(args.minutes) + 1):
        row = next((s for s in samples if s[1] >= minute * 60.0), samples[-1])
        print(f"| {minute} | {row[0]:.0f} | {row[3]:.1f} |")
    after = [s for s in samples if s[1] >= 60.0]
    if len(after) < 10:
        failures.append(f"only {len(after)} memory samples after the first simulated minute")
    else:
        base = after[0][3]
        peak = max(s[3] for s in after)
        print(f"RSS at 1 min {base:.1f} MB, peak after it {peak:.1f} MB (+{peak - base:.1f} MB; bound {FLAT_MB} MB)")
        if peak - base > FLAT_MB:
            failures.append(f"resident memory grew by {peak - base:.1f} MB after the first minute (bound {FLAT_MB})")

    # The summary: complete, one record per avatar, every frame.
    frames = int(round(duration * args.fps)) + 1
    summary = json.loads((out / "summary.json").read_text())
    bodies = summary.get("bodies", [])
    if len(bodies) != args.count:
        failures.append(f"summary.json lists {len(bodies)} bodies, expected {args.count}")
    for body in bodies:
        name = body.get("name", "?")
        dynamics = body.get("dynamics", {})
        if dynamics.get("frames") != frames or body.get("steps") != frames - 1:
            failures.append(f"summary.json: body {name}: {dynamics.get('frames')} frames and {body.get('steps')} "
                            f"steps, expected {frames} and {frames - 1}")
        sigma = dynamics.get("sigma_mean_mm")
        if sigma is None or not math.isfinite(sigma):
            failures.append(f"summary.json: body {name}: mean σ {sigma}")

    # Every frame file, read back.
    checked = 0
    for k in range(args.count):
        avatar = f"avatar_{k:02d}"
        files = sorted(out.glob(f"{avatar}_[0-9]*.vtp"))
        if len(files) != frames:
            failures.append(f"{avatar}: {len(files)} frame files, expected {frames}")
        pvd = (out / f"{avatar}.pvd").read_text()
        if pvd.count("<DataSet") != len(files):
            failures.append(f"{avatar}.pvd lists {pvd.count('<DataSet')} files for {len(files)} written")
        for path in files:
            frame = int(path.stem.rsplit("_", 1)[1])
            problem = check_frame(path, "soft_tissue_displacement", frame / args.fps, args.fps)
            checked += 1
            if problem:
                failures.append(problem)
                if len(failures) > 20:
                    break
    print(f"{checked} frame files read back")
    if not args.keep:
        shutil.rmtree(out, ignore_errors=True)
    for failure in failures:
        print("FAIL:", failure, file=sys.stderr)
    return 1 if failures else 0


if __name__ == "__main__":
    sys.exit(main())
