#!/usr/bin/python3
"""Compare `nbv experiment` folders run under different scene conditions with each other and
with the paper's Table 1 (docs/RESULTS.md).

For each folder: the entropy AUC and coverage AUC of every metric (mean over models and trials),
coverage after 2, 4, 6 and 10 scans, the ties per decision, each metric against random over the
same seeds (paired differences of coverage AUC: mean and standard error), and the distance to
the paper's Table 1 over the models both have (bunny, armadillo, dragon, head).

With --pairs A:B,C:D, each folder also gets paired comparisons: metric A minus metric B over
the same (model, trial) (the same seed, so the same first view) for coverage after 2 scans,
coverage AUC and entropy AUC (mean ± standard error, and on how many models A's mean is the
better), and the mean seconds per decision of each metric.

Usage: compare_conditions.py NAME=DIR [NAME=DIR ...] [--pairs A:B,...]
"""
import argparse
import csv
import math
import os
import sys
from collections import defaultdict

# The order of the metric table (nbv.METRICS); without nbv importable, the results' metrics by name.
try:
    from nbv import METRICS
except ImportError:
    METRICS = ()


def ordered(metrics):
    """`metrics` in the table's order, the others after them by name."""
    return sorted(metrics, key=lambda m: (METRICS.index(m) if m in METRICS else len(METRICS), m))
# The paper's Table 1 (Delmerico et al. 2018) for the models nbv has too: coverage after
# 2, 4, 6, 10 views, coverage AUC, entropy AUC.
PAPER = {
    "armadillo": {"oa": (0.645, 0.882, 0.980, 0.993, 0.893, 0.9466), "uv": (0.594, 0.857, 0.980, 0.994, 0.887, 0.9466),
                  "rsv": (0.647, 0.833, 0.908, 0.986, 0.876, 0.9464), "rse": (0.636, 0.811, 0.933, 0.988, 0.878, 0.9464),
                  "pc": (0.766, 0.950, 0.979, 0.990, 0.908, 0.9465), "vg": (0.776, 0.944, 0.973, 0.981, 0.906, 0.9463),
                  "kr": (0.652, 0.903, 0.974, 0.989, 0.896, 0.9466), "random": (0.643, 0.876, 0.957, 0.986, 0.885, 0.9464)},
    "bunny": {"oa": (0.607, 0.810, 0.915, 0.924, 0.829, 0.9462), "uv": (0.568, 0.800, 0.915, 0.924, 0.824, 0.9462),
              "rsv": (0.605, 0.721, 0.868, 0.916, 0.812, 0.9461), "rse": (0.622, 0.794, 0.869, 0.920, 0.825, 0.9461),
              "pc": (0.707, 0.861, 0.898, 0.917, 0.839, 0.9464), "vg": (0.716, 0.880, 0.908, 0.916, 0.842, 0.9463),
              "kr": (0.575, 0.870, 0.899, 0.910, 0.827, 0.9459), "random": (0.583, 0.781, 0.865, 0.903, 0.813, 0.9460)},
    "dragon": {"oa": (0.494, 0.717, 0.883, 0.936, 0.820, 0.9443), "uv": (0.521, 0.741, 0.907, 0.934, 0.825, 0.9442),
               "rsv": (0.417, 0.615, 0.859, 0.927, 0.798, 0.9440), "rse": (0.461, 0.599, 0.883, 0.930, 0.807, 0.9437),
               "pc": (0.604, 0.789, 0.873, 0.932, 0.836, 0.9447), "vg": (0.622, 0.798, 0.858, 0.910, 0.826, 0.9436),
               "kr": (0.467, 0.795, 0.869, 0.911, 0.812, 0.9443), "random": (0.524, 0.737, 0.820, 0.899, 0.800, 0.9439)},
    "head": {"oa": (0.814, 0.942, 0.957, 0.957, 0.888, 0.9411), "uv": (0.836, 0.946, 0.957, 0.957, 0.890, 0.9410),
             "rsv": (0.812, 0.954, 0.957, 0.959, 0.893, 0.9409), "rse": (0.800, 0.954, 0.957, 0.958, 0.892, 0.9409),
             "pc": (0.924, 0.951, 0.956, 0.957, 0.897, 0.9411), "vg": (0.874, 0.940, 0.944, 0.949, 0.887, 0.9409),
             "kr": (0.798, 0.945, 0.952, 0.955, 0.888, 0.9410), "random": (0.760, 0.925, 0.945, 0.955, 0.882, 0.9409)},
}


def auc(values, start, maximum):
    """The trapezoidal area over iterations 0..N, x scaled to [0, 1], divided by maximum."""
    area, previous = 0.0, start
    for v in values:
        area += 0.5 * (previous + v)
        previous = v
    return area / len(values) / maximum


def mean_se(values):
    n = len(values)
    mean = sum(values) / n
    if n < 2:
        return mean, 0.0
    sd = math.sqrt(sum((v - mean) ** 2 for v in values) / (n - 1))
    return mean, sd / math.sqrt(n)


def load(folder):
    """runs[(model, metric, trial)] = dict with coverage, entropy curves, max entropy, ties, seconds."""
    runs = defaultdict(lambda: {"coverage": [], "entropy": [], "ties": [], "gap": [], "seconds": []})
    with open(os.path.join(folder, "results.csv"), newline="") as f:
        for row in csv.DictReader(f):
            run = runs[(row["model"], row["metric"], int(row["trial"]))]
            run["coverage"].append(float(row["coverage"]))
            run["entropy"].append(float(row["entropy_bits"]))
            run["max"] = float(row["max_entropy_bits"])
            if float(row["seconds_ig"]) > 0 or int(row["ties"]) > 0:
                run["ties"].append(int(row["ties"]))
                run["seconds"].append(float(row["seconds_ig"]))
    for run in runs.values():
        run["auc_coverage"] = auc(run["coverage"], 0.0, 1.0)
        run["auc_entropy"] = auc(run["entropy"], run["max"], run["max"])
    return runs


def summarize(name, runs):
    models = sorted({m for m, _, _ in runs})
    lines = [f"### {name}", "", f"models: {', '.join(models)}; runs: {len(runs)}", "",
             "| metric | coverage @2 | @4 | @6 | @10 | coverage AUC | entropy AUC | ties per decision | "
             "AUC - random (paired) |",
             "|---|---|---|---|---|---|---|---|---|"]
    by_metric = defaultdict(list)
    for (model, metric, trial), run in runs.items():
        by_metric[metric].append((model, trial, run))
    for metric in ordered(by_metric):
        rows = by_metric[metric]
        cells = []
        for k in (2, 4, 6, 10):
            cells.append("%.3f" % (sum(r["coverage"][k - 1] for _, _, r in rows) / len(rows)))
        m_auc, se_auc = mean_se([r["auc_coverage"] for _, _, r in rows])
        m_ent, _ = mean_se([r["auc_entropy"] for _, _, r in rows])
        ties = [t for _, _, r in rows for t in r["ties"]]
        paired = [r["auc_coverage"] - runs[(model, "random", trial)]["auc_coverage"]
                  for model, trial, r in rows if (model, "random", trial) in runs]
        diff = "-" if metric == "random" or not paired else "%+.3f ± %.3f" % mean_se(paired)
        lines.append(f"| {metric} | " + " | ".join(cells) + f" | {m_auc:.3f} ± {se_auc:.3f} | {m_ent:.4f} | "
                     f"{sum(ties) / max(1, len(ties)):.2f} | {diff} |")
    return lines


def paired_lines(runs, pairs):
    """Paired differences A - B over the runs both metrics have (same model and trial)."""
    lines = ["", "| A - B (paired) | coverage @2 | coverage AUC | entropy AUC (lower is better) | "
             "models where A is better: @2 / cov. AUC / ent. AUC |", "|---|---|---|---|---|"]
    models = sorted({m for m, _, _ in runs})
    for a, b in pairs:
        keys = [(m, t) for (m, me, t) in runs if me == a and (m, b, t) in runs]
        if not keys:
            continue
        measures = {
            "c2": lambda r: r["coverage"][1],
            "cov": lambda r: r["auc_coverage"],
            "ent": lambda r: r["auc_entropy"],
        }
        cells, wins = [], []
        for name, f in measures.items():
            diffs = [f(runs[(m, a, t)]) - f(runs[(m, b, t)]) for m, t in keys]
            cells.append("%+.4f ± %.4f" % mean_se(diffs))
            better = 0
            for model in models:
                d = [f(runs[(m, a, t)]) - f(runs[(m, b, t)]) for m, t in keys if m == model]
                if d and (sum(d) < 0 if name == "ent" else sum(d) > 0):
                    better += 1
            wins.append(str(better))
        lines.append(f"| {a} - {b} | " + " | ".join(cells) + f" | {' / '.join(wins)} of {len(models)} |")
    seconds = defaultdict(list)
    for (_, metric, _), run in runs.items():
        seconds[metric] += run["seconds"]
    lines += ["", "| metric | decisions | s per decision (mean) |", "|---|---:|---:|"]
    for metric in ordered(m for m in seconds if seconds.get(m)):
        lines.append(f"| {metric} | {len(seconds[metric])} | {sum(seconds[metric]) / len(seconds[metric]):.4f} |")
    return lines


def table1_means(rows):
    """The mean of runs `rows` in Table 1's columns: coverage after 2, 4, 6, 10 views, coverage
    AUC, entropy AUC."""
    means = [sum(r["coverage"][k - 1] for r in rows) / len(rows) for k in (2, 4, 6, 10)]
    means.append(sum(r["auc_coverage"] for r in rows) / len(rows))
    means.append(sum(r["auc_entropy"] for r in rows) / len(rows))
    return means


def paper_distance(runs):
    """RMS difference to the paper's Table 1 over its shared models and metrics: coverage at
    2/4/6/10 and coverage AUC (together), and entropy AUC (alone)."""
    coverage_sq, entropy_sq, n_cov, n_ent = 0.0, 0.0, 0, 0
    for model, table in PAPER.items():
        for metric, paper in table.items():
            rows = [r for (m, me, _), r in runs.items() if m == model and me == metric]
            if not rows:
                continue
            ours = table1_means(rows)
            for a, b in zip(ours[:5], paper[:5]):
                coverage_sq += (a - b) ** 2
                n_cov += 1
            entropy_sq += (ours[5] - paper[5]) ** 2
            n_ent += 1
    if n_cov == 0:
        return None
    return math.sqrt(coverage_sq / n_cov), math.sqrt(entropy_sq / n_ent)


def table1_lines(runs):
    """The paper's Table 1 beside this run's means, per shared model and metric: coverage after
    2 and 10 views, coverage AUC and entropy AUC, each as paper / ours."""
    lines = ["", "| model | metric | coverage @2 paper / ours | @10 | coverage AUC | entropy AUC |",
             "|---|---|---|---|---|---|"]
    for model, table in sorted(PAPER.items()):
        for metric in ordered(table):
            rows = [r for (m, me, _), r in runs.items() if m == model and me == metric]
            if not rows:
                continue
            paper = table[metric]
            ours = table1_means(rows)
            cells = [f"{paper[0]:.3f} / {ours[0]:.3f}", f"{paper[3]:.3f} / {ours[3]:.3f}",
                     f"{paper[4]:.3f} / {ours[4]:.3f}", f"{paper[5]:.4f} / {ours[5]:.4f}"]
            lines.append(f"| {model} | {metric} | " + " | ".join(cells) + " |")
    return lines


def main():
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("folders", nargs="+", help="NAME=DIR of an nbv experiment")
    parser.add_argument("--pairs", default="", help="comma-separated A:B metric pairs to compare over the same seeds")
    parser.add_argument("--table1", action="store_true", help="the paper's Table 1 beside each condition's means")
    args = parser.parse_args()
    pairs = [tuple(p.split(":", 1)) for p in args.pairs.split(",") if p]
    for pair in pairs:
        if len(pair) != 2 or (METRICS and (pair[0] not in METRICS or pair[1] not in METRICS)):
            print(f"compare_conditions: --pairs: '{':'.join(pair)}' is not A:B of two metrics ({', '.join(METRICS)})",
                  file=sys.stderr)
            return 2
    out = ["| condition | RMS to Table 1: coverage (@2/4/6/10, AUC) | RMS to Table 1: entropy AUC | "
           "mean entropy AUC |", "|---|---:|---:|---:|"]
    sections = []
    for item in args.folders:
        name, _, folder = item.partition("=")
        try:
            runs = load(folder)
        except (OSError, KeyError, ValueError) as error:
            print(f"compare_conditions: {folder}: {error}", file=sys.stderr)
            return 1
        short = [key for key, run in runs.items() if len(run["coverage"]) < 10]
        if short:
            model, metric, trial = short[0]
            print(f"compare_conditions: {folder}: the run of {model}, {metric}, trial {trial} has "
                  f"{len(runs[short[0]]['coverage'])} scans; the tables need at least 10 (coverage @10)", file=sys.stderr)
            return 1
        distance = paper_distance(runs)
        mean_entropy = sum(r["auc_entropy"] for r in runs.values()) / len(runs)
        if distance:
            out.append(f"| {name} | {distance[0]:.4f} | {distance[1]:.4f} | {mean_entropy:.4f} |")
        sections += [""] + summarize(name, runs)
        if pairs:
            sections += paired_lines(runs, pairs)
        if args.table1:
            sections += table1_lines(runs)
    print("\n".join(out + sections))
    return 0


if __name__ == "__main__":
    sys.exit(main())
