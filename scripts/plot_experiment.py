#!/usr/bin/python3
"""Plot an `nbv experiment` like the paper's Fig. 3: per model, surface coverage and map entropy
against iteration, one line per metric (the mean over trials) with a band for the spread
(mean +- one standard deviation).

Usage: plot_experiment.py RESULTS.csv --out-dir DIR   (writes DIR/<model>.png)
"""
import argparse
import csv
import math
import os
import sys
from collections import defaultdict

import matplotlib

matplotlib.use("Agg")  # files only, no display
import matplotlib.pyplot as plt  # noqa: E402
from matplotlib.ticker import MaxNLocator  # noqa: E402

METRIC_ORDER = ["entropy", "oa", "uv", "rsv", "rse", "pc", "vg", "kr", "random"]


def mean_std(values):
    mean = sum(values) / len(values)
    if len(values) < 2:
        return mean, 0.0
    return mean, math.sqrt(sum((v - mean) ** 2 for v in values) / (len(values) - 1))


def main() -> int:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("results", help="results.csv of nbv experiment")
    parser.add_argument("--out-dir", required=True)
    args = parser.parse_args()

    # curves[model][metric][trial] = {iteration: (coverage, entropy)}; max entropy per model
    curves = defaultdict(lambda: defaultdict(lambda: defaultdict(dict)))
    max_entropy = {}
    try:
        with open(args.results, newline="", encoding="utf-8") as f:
            for row in csv.DictReader(f):
                curves[row["model"]][row["metric"]][int(row["trial"])][int(row["iteration"])] = (
                    float(row["coverage"]), float(row["entropy_bits"]))
                max_entropy[row["model"]] = float(row["max_entropy_bits"])
    except (OSError, KeyError, ValueError) as error:
        print(f"plot_experiment: {args.results}: {error}", file=sys.stderr)
        return 1

    os.makedirs(args.out_dir, exist_ok=True)
    for model, by_metric in sorted(curves.items()):
        fig, (ax_cov, ax_ent) = plt.subplots(1, 2, figsize=(12, 4.5))
        metrics = sorted(by_metric, key=lambda m: (METRIC_ORDER.index(m) if m in METRIC_ORDER else 99, m))
        for metric in metrics:
            trials = by_metric[metric].values()
            last = min(max(t) for t in trials)  # iterations every trial reached
            xs = list(range(0, last + 1))
            for ax, index, start in ((ax_cov, 0, 0.0), (ax_ent, 1, max_entropy[model])):
                stats = [mean_std([start if x == 0 else t[x][index] for t in trials]) for x in xs]
                scale = 1.0 if index == 0 else 1e-6
                mean = [m * scale for m, _ in stats]
                low = [(m - s) * scale for m, s in stats]
                high = [(m + s) * scale for m, s in stats]
                (line,) = ax.plot(xs, mean, label=metric, linewidth=1.5)
                ax.fill_between(xs, low, high, color=line.get_color(), alpha=0.15, linewidth=0)
        ax_cov.set_title(f"{model}: surface coverage (Eq. 15)")
        ax_cov.set_ylabel("coverage")
        ax_cov.set_ylim(0.0, 1.0)
        ax_ent.set_title(f"{model}: map entropy (Eq. 16)")
        ax_ent.set_ylabel("entropy [Mbit]")
        for ax in (ax_cov, ax_ent):
            ax.set_xlabel("iteration")
            ax.xaxis.set_major_locator(MaxNLocator(integer=True))
            ax.grid(alpha=0.3)
        ax_cov.legend(fontsize=8, loc="lower right", ncol=2)
        fig.tight_layout()
        path = os.path.join(args.out_dir, f"{model}.png")
        fig.savefig(path, dpi=110)
        plt.close(fig)
        print(f"wrote {path}")
    return 0


if __name__ == "__main__":
    sys.exit(main())
