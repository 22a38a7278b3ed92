#!/usr/bin/python3
"""Plot surface coverage and map entropy against iteration for `nbv reconstruct --json` runs.

Usage: plot_reconstruction.py RUN.json [RUN.json ...] --out PLOT.png
One line per run, labelled by model and metric; iteration 0 is the empty map (coverage 0,
entropy maximal), as in SEMANTICS.md "Simulation and evaluation".
"""
import argparse
import json
import sys

import matplotlib

matplotlib.use("Agg")  # files only, no display
import matplotlib.pyplot as plt  # noqa: E402
from matplotlib.ticker import MaxNLocator  # noqa: E402


def main() -> int:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("runs", nargs="+", help="JSON files written by nbv reconstruct --json")
    parser.add_argument("--out", required=True, help="PNG to write")
    args = parser.parse_args()

    fig, (ax_cov, ax_ent) = plt.subplots(1, 2, figsize=(11, 4.2))
    for path in args.runs:
        try:
            with open(path, encoding="utf-8") as f:
                run = json.load(f)
            iterations = [0] + [it["iteration"] for it in run["iterations"]]
            coverage = [0.0] + [it["coverage"] for it in run["iterations"]]
            entropy = [run["max_entropy_bits"]] + [it["entropy_bits"] for it in run["iterations"]]
        except (OSError, ValueError, KeyError, TypeError) as error:
            print(f"plot_reconstruction: {path}: {error}", file=sys.stderr)
            return 1
        label = f'{run["model"]}, {run["metric"]} (seed {run["seed"]})'
        ax_cov.plot(iterations, coverage, marker="o", markersize=3, label=label)
        ax_ent.plot(iterations, [e / 1e6 for e in entropy], marker="o", markersize=3, label=label)
    for ax in (ax_cov, ax_ent):
        ax.xaxis.set_major_locator(MaxNLocator(integer=True))
    ax_cov.set_xlabel("iteration")
    ax_cov.set_ylabel("surface coverage (Eq. 15)")
    ax_cov.set_ylim(0.0, 1.0)
    ax_cov.grid(alpha=0.3)
    ax_ent.set_xlabel("iteration")
    ax_ent.set_ylabel("map entropy [Mbit] (Eq. 16)")
    ax_ent.grid(alpha=0.3)
    ax_cov.legend(fontsize=8, loc="lower right")
    fig.tight_layout()
    fig.savefig(args.out, dpi=120)
    print(f"wrote {args.out}")
    return 0


if __name__ == "__main__":
    sys.exit(main())
