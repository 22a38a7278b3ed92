#!/usr/bin/python3
"""Plots the cost of a decision against the number of candidates from the table that
`nbv_anytime_study scaling` prints (docs/performance-log.md, "Anytime decisions").

Usage: nbv_anytime_study scaling ... | tee scaling.md; plot_anytime_scaling.py scaling.md --out scaling.png
"""
import argparse
import sys
from collections import defaultdict

import matplotlib

matplotlib.use("Agg")
import matplotlib.pyplot as plt  # noqa: E402


def main():
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("table")
    parser.add_argument("--out", required=True)
    args = parser.parse_args()
    series = defaultdict(lambda: ([], [], []))  # utility -> candidates, exhaustive s, anytime s
    with open(args.table) as f:
        for line in f:
            cells = [c.strip() for c in line.strip().strip("|").split("|")]
            if len(cells) < 4 or not cells[0].isdigit():
                continue
            n, utility, exhaustive, anytime = int(cells[0]), cells[1], float(cells[2]), float(cells[3])
            s = series[utility]
            s[0].append(n)
            s[1].append(exhaustive)
            s[2].append(anytime)
    if not series:
        print(f"plot_anytime_scaling: {args.table}: no table rows", file=sys.stderr)
        return 1
    fig, ax = plt.subplots(figsize=(6, 4))
    for utility, (n, exhaustive, anytime) in sorted(series.items()):
        ax.plot(n, exhaustive, "o-", label=f"{utility}, exhaustive")
        ax.plot(n, anytime, "s--", label=f"{utility}, anytime")
    ax.set_xscale("log")
    ax.set_yscale("log")
    ax.set_xlabel("candidate views")
    ax.set_ylabel("seconds per decision")
    ax.set_title("bunny-3, full ray set, 2 threads")
    ax.grid(True, which="both", alpha=0.3)
    ax.legend(fontsize=8)
    fig.tight_layout()
    fig.savefig(args.out, dpi=110)
    print(f"wrote {args.out}")
    return 0


if __name__ == "__main__":
    sys.exit(main())
