#!/usr/bin/env python3
"""Draws docs/verification.md's figures from what the verification tests measured.

Usage (after a build):
    SFLSH_VERIFICATION_OUT=out/verification build/release/tests/test_verification
    scripts/plot_verification.py out/verification/convergence.csv --febio-run out/febio_block \
        --out docs/results/verification

convergence.csv has `study,case,h,error` rows (tests/verification/convergence_log.hpp). --febio-run names a
`sflsh verify` run folder of examples/verify/febio_block/block.toml, drawn against FEBio's trajectory of the
same problem (tests/data/febio/e_fung_k1e-3_dt960_tet4g4.csv). Writes time_order.png, space_order.png and
febio_block.png (viridis colours; axes with their units).
"""
import argparse
import collections
import csv
import math
import pathlib

import matplotlib

matplotlib.use("Agg")
import matplotlib.pyplot as plt  # noqa: E402

ROOT = pathlib.Path(__file__).resolve().parent.parent
FEBIO = ROOT / "tests" / "data" / "febio" / "e_fung_k1e-3_dt960_tet4g4.csv"
CENTRE_NODE = 363 + 5 + 11 * 5  # the top face's centre node (x = y = 5 cm)


def read_convergence(path):
    series = collections.defaultdict(list)
    with open(path, newline="") as f:
        for row in csv.DictReader(f):
            series[(row["study"], row["case"])].append((float(row["h"]), float(row["error"])))
    return {key: sorted(set(values)) for key, values in series.items()}


def slope_guide(ax, h, error, order, label):
    """A dashed line of the given order through the finest point."""
    h0, e0 = h[-1], error[-1]
    ax.loglog([h[0], h0], [e0 * (h[0] / h0) ** order, e0], "k--", lw=0.8)
    ax.annotate(label, (h[0], e0 * (h[0] / h0) ** order), fontsize=8, ha="left", va="bottom")


def plot_orders(series, studies, title, xlabel, path):
    colours = plt.cm.viridis
    panels = [s for s in studies if any(k[0] in s[0] for k in series)]
    if not panels:
        return False
    fig, axes = plt.subplots(1, len(panels), figsize=(5.2 * len(panels), 4.2), squeeze=False)
    for ax, (names, panel_title, ylabel, guides) in zip(axes[0], panels):
        keys = sorted(k for k in series if k[0] in names)
        for i, key in enumerate(keys):
            points = series[key]
            case = names[key[0]] or key[1]
            h = [p[0] for p in points][::-1]
            e = [p[1] for p in points][::-1]
            order = math.log2(e[-2] / e[-1]) if len(e) >= 2 else float("nan")
            ax.loglog(h, e, "o-", color=colours(i / max(1, len(keys) - 1) * 0.85),
                      label=f"{case} (observed order {order:.2f})")
        first = series[keys[0]]
        hs = sorted(p[0] for p in first)[::-1]
        es = [p[1] for p in sorted(first)][::-1]
        for order in guides:
            slope_guide(ax, hs, es, order, f"order {order}")
        ax.set_xlabel(xlabel)
        ax.set_ylabel(ylabel)
        ax.set_title(panel_title, fontsize=10)
        ax.grid(True, which="both", lw=0.3)
        ax.legend(fontsize=8)
    fig.suptitle(title)
    fig.tight_layout()
    fig.savefig(path, dpi=120)
    plt.close(fig)
    return True


def read_history(path, node):
    """t [s] and the node's displacement relative to the driven bone [mm] (x, z)."""
    t, ux, uz = [], [], []
    with open(path, newline="") as f:
        for row in csv.DictReader(f):
            if int(row["node"]) != node:
                continue
            time = float(row["t"])
            bone = 0.0025 * (1.0 - math.cos(4.0 * math.pi * time)) ** 2
            t.append(time)
            ux.append(1e3 * float(row["ux"]))
            uz.append(1e3 * (float(row["uz"]) - bone))
    return t, ux, uz


def plot_febio(run, path):
    ours = read_history(run / "history.csv", CENTRE_NODE)
    febio = read_history(FEBIO, CENTRE_NODE)
    fig, (top, bottom) = plt.subplots(2, 1, figsize=(7, 5.6), sharex=True, gridspec_kw={"height_ratios": [2, 1]})
    top.plot(febio[0], febio[2], "-", color=plt.cm.viridis(0.15), lw=3, label="FEBio 4.11, Newmark 1/960 s, TET4G4")
    top.plot(ours[0], ours[2], "--", color=plt.cm.viridis(0.8), lw=1.5,
             label="sflsh full space, Newmark 1/960 s, consistent mass")
    top.set_ylabel("top-face centre: u_z − u_bone [mm]")
    top.set_title("Driven flesh-layer block: the top face's motion relative to the bone", fontsize=10)
    top.grid(True, lw=0.3)
    top.legend(fontsize=8)
    febio_at = {round(960 * t): u for t, u in zip(febio[0], febio[2])}  # FEBio logged every 1/60 s, ours every step
    pairs = [(t, abs(u - febio_at[round(960 * t)])) for t, u in zip(ours[0], ours[2])
             if round(960 * t) in febio_at and t > 0.0]
    bottom.semilogy([p[0] for p in pairs], [max(1e3 * p[1], 1e-9) for p in pairs], color=plt.cm.viridis(0.5), lw=1)
    bottom.set_xlabel("time t [s]")
    bottom.set_ylabel("|sflsh − FEBio| [µm]")
    bottom.grid(True, which="both", lw=0.3)
    fig.tight_layout()
    fig.savefig(path, dpi=120)
    plt.close(fig)


def main():
    parser = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    parser.add_argument("convergence", type=pathlib.Path)
    parser.add_argument("--febio-run", type=pathlib.Path)
    parser.add_argument("--out", type=pathlib.Path, default=ROOT / "docs" / "results" / "verification")
    args = parser.parse_args()
    args.out.mkdir(parents=True, exist_ok=True)
    series = read_convergence(args.convergence)
    plot_orders(series, [
        ({"time_block": None}, "FEBio block, against the SUNDIALS reference", "error / largest motion", (1, 2)),
        ({"time_body_layer": None}, "coarse body layer, |u_h − u_h/2|", "difference / largest displacement",
         (1, 2)),
    ], "Convergence in time", "step h [s]", args.out / "time_order.png")
    plot_orders(series, [
        ({"space_manufactured": None}, "manufactured static solution", "relative error", (1, 2)),
        ({"space_block": "free sides", "space_block_sliding": "sliding sides"}, "block under gravity, top face",
         "change between levels / displacement", (1, 2)),
    ], "Convergence in space (linear tets)", "cell size h [m]", args.out / "space_order.png")
    if args.febio_run:
        plot_febio(args.febio_run, args.out / "febio_block.png")


if __name__ == "__main__":
    main()
