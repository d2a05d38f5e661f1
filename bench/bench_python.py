#!/usr/bin/env python3
"""Benchmark: what the Python module costs on top of the C++ it wraps.

  - import time of `import sflsh` in a fresh interpreter (median of --imports runs; NumPy's import, which the
    module triggers only when it first hands out an array, is listed beside it);
  - the overhead of a Python `Simulation.step()` against the C++ step it runs (scene::BodySimulation::step():
    the solver's steps plus the frame's recording), for one body with the reduced model: per frame, the wall
    time of the Python call minus `last_step_seconds` (the C++ wall time of the same call), over --frames frames.
    The solver's own share (summary "frames" seconds) is listed beside it.

Prints a table and writes JSON like the C++ benchmarks (bench/bench_reduced.cpp).

Usage: PYTHONPATH=build/release/python /usr/bin/python3 bench/bench_python.py [--frames 120] [--mesh coarse]
           [--subject OPEN_TRAIN_1] [--motion jiggle_on_toes] [--imports 5] [--cache DIR] [--out bench_python.json]
"""
import argparse
import json
import os
import statistics
import subprocess
import sys
import time


def import_seconds(module, runs):
    code = f"import time; t = time.perf_counter(); import {module}; print(time.perf_counter() - t)"
    times = [float(subprocess.run([sys.executable, "-c", code], capture_output=True, text=True, check=True,
                                  env=os.environ).stdout) for _ in range(runs)]
    return statistics.median(times)


def main():
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--frames", type=int, default=120)
    parser.add_argument("--mesh", default="coarse")
    parser.add_argument("--subject", default="OPEN_TRAIN_1")
    parser.add_argument("--motion", default="jiggle_on_toes")
    parser.add_argument("--imports", type=int, default=5)
    parser.add_argument("--cache", default=None)
    parser.add_argument("--out", default="bench_python.json")
    args = parser.parse_args()

    numpy_s = import_seconds("numpy", args.imports)
    sflsh_s = import_seconds("sflsh", args.imports)

    import sflsh
    t0 = time.perf_counter()
    # record=False: the overhead of a step itself; keeping the states for write() copies x and w per frame.
    sim = sflsh.Simulation(subject=args.subject, motion=args.motion, frames=args.frames + 1, solver="reduced",
                           mesh=args.mesh, cache=args.cache, record=False)
    setup_s = time.perf_counter() - t0
    python_s, cpp_s = [], []
    while not sim.finished:
        t = time.perf_counter()
        sim.step()
        python_s.append(time.perf_counter() - t)
        cpp_s.append(sim.last_step_seconds)
    summary = sim.summary()
    solver_s = [f["seconds"] for f in summary["frames"][1:]]
    overhead_s = [p - c for p, c in zip(python_s, cpp_s)]
    us = 1e6
    recording_s = [c - s for c, s in zip(cpp_s, solver_s)]
    rows = [
        ("python_step", "Python step() wall", python_s),
        ("cpp_step", "C++ step (BodySimulation::step)", cpp_s),
        ("solver", "  of which the solver's steps", solver_s),
        ("recording", "  of which the frame's record (σ, energies)", recording_s),
        ("overhead", "Python overhead (wall − C++)", overhead_s),
    ]
    rows = [(key, name, statistics.median(v) * us, sum(v) / len(v) * us) for key, name, v in rows]
    overhead_share = statistics.median(overhead_s) / statistics.median(cpp_s)
    print(f"import sflsh: {sflsh_s * 1e3:.1f} ms (import numpy: {numpy_s * 1e3:.1f} ms), median of {args.imports} fresh "
          f"interpreters")
    print(f"Simulation setup: {setup_s:.2f} s ({summary['reduced']['cache']} reduced model, {summary['mesh']['tets']} tets, "
          f"{summary['reduced']['coordinates']} coordinates)\n")
    print(f"{'per frame (reduced, ' + args.mesh + ', ' + str(len(python_s)) + ' frames)':<44} {'median µs':>10} {'mean µs':>10}")
    for _, name, median, mean in rows:
        print(f"{name:<44} {median:>10.1f} {mean:>10.1f}")
    print(f"\noverhead / C++ step: {100 * overhead_share:.2f} % (median)")
    with open(args.out, "w") as f:
        json.dump({"benchmark": "python", "python": sys.version.split()[0], "mesh": args.mesh, "subject": args.subject,
                   "motion": args.motion, "frames": len(python_s),
                   "import_ms": {"sflsh": sflsh_s * 1e3, "numpy": numpy_s * 1e3},
                   "setup_seconds": setup_s, "reduced_cache": summary["reduced"]["cache"],
                   "step_us": {key: {"median": median, "mean": mean} for key, _, median, mean in rows},
                   "overhead_share": overhead_share}, f, indent=2)
    print(f"wrote {args.out}")


if __name__ == "__main__":
    main()
