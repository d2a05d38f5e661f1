#!/usr/bin/env python3
"""Jiggle two bodies of different shape and plot where their soft tissue moves.

Loads the open body, gives each of two subjects (default: OPEN_TRAIN_4, tall and thin, and OPEN_TRAIN_5, heavy
with a large belly) the material the shipped shape model predicts for its β (data/shape_models/default.toml,
sflsh.Material.from_shape_model), simulates `jiggle_on_toes` with the reduced model on the coarse layer, and
plots the dynamics amplitude σ per vertex (docs/physics.md §4) on each shaped body, front view, to a PNG (viridis,
with its colour bar). Each simulation also writes the run folder `sflsh simulate` writes (Simulation.write: body.xmf +
body.h5, dynamics.vtp, summary.json) to <out>_runs/<subject>/, for ParaView or `sflsh render --run`.

    PYTHONPATH=build/release/python /usr/bin/python3 examples/python_jiggle.py --out jiggle.png

help(sflsh.Simulation) lists every keyword with its default; python/sflsh.pyi is the module's type stub.

About 15 s on 2 cores for 120 frames each, the two reduced models built on the way (the template mesh cached).
"""
import argparse
import os
import time

import matplotlib

matplotlib.use("Agg")   # no display needed
import matplotlib.pyplot as plt
import numpy as np

import sflsh


def simulate(subject, frames, cache, runs):
    material = sflsh.Material.from_shape_model(subject=subject)
    sim = sflsh.Simulation(subject=subject, motion="jiggle_on_toes", frames=frames, solver="reduced", mesh="coarse",
                           material=material, cache=cache)
    t0 = time.perf_counter()
    sim.run()
    seconds = time.perf_counter() - t0
    sigma, _, _ = sim.sigma()
    summary = sim.summary()
    sim.write(os.path.join(runs, subject))   # the run folder of `sflsh simulate --out runs/<subject>`
    print(f"{subject}: {frames} frames in {seconds:.2f} s, mean σ = {summary['dynamics']['sigma_mean_mm']:.2f} mm, "
          f"max σ = {summary['dynamics']['sigma_max_mm']:.2f} mm")
    return sim.beta, 1e3 * sigma, summary["dynamics"]["sigma_mean_mm"], sim.time   # mm, s


def main():
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--subjects", default="OPEN_TRAIN_4,OPEN_TRAIN_5", help="two (or more) subject names")
    parser.add_argument("--frames", type=int, default=120, help="frames at 60 fps (default: 2 s)")
    parser.add_argument("--cache", default=None, help="cache folder for meshes and reduced models")
    parser.add_argument("--out", default="python_jiggle.png", help="the PNG to write")
    parser.add_argument("--runs", default=None, help="folder of the run folders (default: <out without .png>_runs)")
    args = parser.parse_args()

    body = sflsh.Body()
    subjects = args.subjects.split(",")
    runs = args.runs or os.path.splitext(args.out)[0] + "_runs"
    results = [simulate(s, args.frames, args.cache, runs) for s in subjects]
    top = max(float(np.percentile(sigma, 99.5)) for _, sigma, _, _ in results)

    fig, axes = plt.subplots(1, len(subjects), figsize=(4 * len(subjects), 6), constrained_layout=True)
    for ax, subject, (beta, sigma, mean, end) in zip(np.atleast_1d(axes), subjects, results):
        shaped = body.shape(beta)
        order = np.argsort(shaped[:, 2])   # back to front, so the front of the body is drawn last
        points = ax.scatter(shaped[order, 0], shaped[order, 1], c=sigma[order], s=2, cmap="viridis", vmin=0, vmax=top)
        ax.set_title(f"{subject}\njiggle_on_toes, t = 0 to {end:.2f} s\nmean σ over the region {mean:.2f} mm",
                     fontsize=10)
        ax.set_aspect("equal")
        ax.axis("off")
    fig.colorbar(points, ax=axes, shrink=0.6, label="σ [mm] (reduced model; above the 99.5th percentile saturates)")
    os.makedirs(os.path.dirname(os.path.abspath(args.out)), exist_ok=True)
    fig.savefig(args.out, dpi=120)
    print(f"wrote {args.out} and the run folders in {runs}/")


if __name__ == "__main__":
    main()
