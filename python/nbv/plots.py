"""nbv.plots: surface coverage and map entropy against iteration, drawn with matplotlib.

    python3 -m nbv.plots experiment RESULTS.csv --out-dir DIR   # DIR/<model>.png, like the paper's Fig. 3
    python3 -m nbv.plots runs RUN.json [RUN.json ...] --out PLOT.png

`experiment` draws, per model of an `nbv experiment` results.csv, one line per metric (the mean
over trials) with a band of one standard deviation; `runs` draws runs of `nbv reconstruct
--json` (or nbv.save_run()), one line each. Iteration 0 is the empty map: coverage 0, entropy
maximal (docs/SEMANTICS.md, "Simulation and evaluation"). `nbv experiment` and `make demo` run
this module; from Python, call plot_experiment() and plot_runs().
"""

import argparse as _argparse
import csv as _csv
import math as _math
import os as _os
import sys as _sys
from collections import defaultdict as _defaultdict

from . import METRICS as _METRICS
from . import load_run as _load_run

__all__ = ["plot_experiment", "plot_runs", "main"]


def _pyplot():
    """matplotlib's pyplot drawing to files only, or an error saying where matplotlib comes from."""
    try:
        import matplotlib
    except ImportError as error:
        raise ImportError(f"nbv.plots needs matplotlib, which {_sys.executable} lacks: on Debian, "
                          "apt-get install python3-matplotlib (or pip install matplotlib)") from error
    matplotlib.use("Agg")
    import matplotlib.pyplot as plt
    return plt


def _mean_std(values):
    mean = sum(values) / len(values)
    if len(values) < 2:
        return mean, 0.0
    return mean, _math.sqrt(sum((v - mean) ** 2 for v in values) / (len(values) - 1))


def _metric_order(metric):
    """Built-in metrics in the package's order (nbv.METRICS), weighted sums after them."""
    return (_METRICS.index(metric) if metric in _METRICS else len(_METRICS), metric)


def _read_results(path):
    """curves[model][metric][trial][iteration] = (coverage, entropy bits), and each model's maximum entropy."""
    curves = _defaultdict(lambda: _defaultdict(lambda: _defaultdict(dict)))
    max_entropy = {}
    try:
        with open(path, newline="", encoding="utf-8") as f:
            for line, row in enumerate(_csv.DictReader(f), start=2):
                try:
                    curves[row["model"]][row["metric"]][int(row["trial"])][int(row["iteration"])] = (
                        float(row["coverage"]), float(row["entropy_bits"]))
                    max_entropy[row["model"]] = float(row["max_entropy_bits"])
                except (KeyError, TypeError, ValueError) as error:
                    raise ValueError(f"{path}:{line}: not a row of nbv experiment's results.csv ({error})") from None
    except OSError as error:
        raise OSError(f"{path}: cannot read ({error.strerror or error})") from None
    if not curves:
        raise ValueError(f"{path}: holds no run")
    return curves, max_entropy


def plot_experiment(results, out_dir):
    """plot_experiment(results, out_dir) -> list of paths

    Writes out_dir/<model>.png for each model of `results` (the path of an `nbv experiment`
    results.csv): coverage and entropy against iteration, a line per metric, a band of one
    standard deviation. Raises ValueError or OSError naming the file and line.
    """
    curves, max_entropy = _read_results(_os.fspath(results))
    plt = _pyplot()
    from matplotlib.ticker import MaxNLocator
    _os.makedirs(out_dir, exist_ok=True)
    written = []
    for model, by_metric in sorted(curves.items()):
        fig, (ax_cov, ax_ent) = plt.subplots(1, 2, figsize=(12, 4.5))
        for metric in sorted(by_metric, key=_metric_order):
            trials = by_metric[metric].values()
            last = min(max(t) for t in trials)  # the iterations every trial reached
            xs = list(range(0, last + 1))
            for ax, index, start, scale in ((ax_cov, 0, 0.0, 1.0), (ax_ent, 1, max_entropy[model], 1e-6)):
                stats = [_mean_std([start if x == 0 else t[x][index] for t in trials]) for x in xs]
                (line,) = ax.plot(xs, [m * scale for m, _ in stats], label=metric, linewidth=1.5)
                ax.fill_between(xs, [(m - s) * scale for m, s in stats], [(m + s) * scale for m, s in stats],
                                color=line.get_color(), alpha=0.15, linewidth=0)
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
        path = _os.path.join(out_dir, f"{model}.png")
        fig.savefig(path, dpi=110)
        plt.close(fig)
        written.append(path)
    return written


def _run_curves(run, where):
    """(iterations, coverage, entropy bits) of a run's dict, iteration 0 the empty map."""
    try:
        its = run["iterations"]
        return ([0] + [int(it["iteration"]) for it in its], [0.0] + [float(it["coverage"]) for it in its],
                [float(run["max_entropy_bits"])] + [float(it["entropy_bits"]) for it in its])
    except (KeyError, TypeError, ValueError) as error:
        raise ValueError(f"{where}: not a run of nbv reconstruct --json ({error})") from None


def plot_runs(runs, out):
    """plot_runs(runs, out) -> out

    Writes the PNG `out`: coverage and entropy against iteration, a line per run. `runs` are
    paths of `nbv reconstruct --json` files or run dicts (reconstruct(), load_run()).
    """
    curves = []
    for i, run in enumerate(runs):
        where = f"runs[{i}]"
        if not isinstance(run, dict):
            where = _os.fspath(run)
            run = _load_run(where)  # nbv.FileError (an OSError) naming the file
        label = f'{run.get("model", "?")}, {run.get("metric", "?")} (seed {run.get("seed", "?")})'
        curves.append((label,) + _run_curves(run, where))
    if not curves:
        raise ValueError("plot_runs: no run given")
    plt = _pyplot()
    from matplotlib.ticker import MaxNLocator
    fig, (ax_cov, ax_ent) = plt.subplots(1, 2, figsize=(11, 4.2))
    for label, iterations, coverage, entropy in curves:
        ax_cov.plot(iterations, coverage, marker="o", markersize=3, label=label)
        ax_ent.plot(iterations, [e / 1e6 for e in entropy], marker="o", markersize=3, label=label)
    for ax in (ax_cov, ax_ent):
        ax.xaxis.set_major_locator(MaxNLocator(integer=True))
        ax.set_xlabel("iteration")
        ax.grid(alpha=0.3)
    ax_cov.set_ylabel("surface coverage (Eq. 15)")
    ax_cov.set_ylim(0.0, 1.0)
    ax_ent.set_ylabel("map entropy [Mbit] (Eq. 16)")
    ax_cov.legend(fontsize=8, loc="lower right")
    fig.tight_layout()
    fig.savefig(out, dpi=120)
    plt.close(fig)
    return out


def main(argv=None):
    """The command line: `python3 -m nbv.plots experiment|runs ...`; returns the exit status."""
    parser = _argparse.ArgumentParser(prog="python3 -m nbv.plots", description=__doc__.splitlines()[0])
    commands = parser.add_subparsers(dest="command", required=True)
    experiment = commands.add_parser("experiment", help="per model of an nbv experiment's results.csv: DIR/<model>.png")
    experiment.add_argument("results", help="results.csv of nbv experiment")
    experiment.add_argument("--out-dir", required=True, help="the folder of the PNGs")
    runs = commands.add_parser("runs", help="runs of nbv reconstruct --json in one PNG")
    runs.add_argument("runs", nargs="+", help="JSON files of nbv reconstruct --json or nbv.save_run()")
    runs.add_argument("--out", required=True, help="the PNG to write")
    args = parser.parse_args(argv)
    try:
        if args.command == "experiment":
            written = plot_experiment(args.results, args.out_dir)
        else:
            written = [plot_runs(args.runs, args.out)]
    except (OSError, ValueError, ImportError) as error:
        print(f"nbv.plots: {error}", file=_sys.stderr)
        return 1
    for path in written:
        print(f"wrote {path}")
    return 0


if __name__ == "__main__":
    _sys.exit(main())
