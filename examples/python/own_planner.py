#!/usr/bin/python3
"""A planner of your own inside nbv's NBV loop: nbv.reconstruct(model, metric=callable).

nbv runs the paper's loop (render, integrate, decide, move) and at each decision calls your
function with the state of the run: the map (a copy), the viewspace, the views taken, the open
candidates, and two functions that compute per-candidate arrays on the run's own snapshot and
rays: metric_values("pc,oa") (the built-in metrics, a (C, k) array) and visible_voxels(c) (the
voxels the rays of candidate c reach, with their visibility). It returns a gain per candidate;
nbv chooses by Eq. 12 and 13 as for a built-in metric and records the run as any other.

The formulation here: the unknown voxels a candidate's rays reach, each weighted by its
visibility and by the inverse of its distance from the camera (nearer unknown space is seen at
a finer grain). It runs beside the built-in pc and beside a planner that returns pc's own
values through metric_values, which must be the pc run itself: the example exits 1 if not.

    PYTHONPATH=build/python /usr/bin/python3 examples/python/own_planner.py [--seeds 0 1] [--iterations 6]
"""
import argparse
import sys

import numpy as np

import nbv


def unknown_by_distance(state):
    """Each candidate's reached unknown voxels (P_o between the free and occupied thresholds,
    never-measured voxels included), weighted by visibility / distance."""
    world = state["map"]
    free, occupied = world.config["free_threshold"], world.config["occupied_threshold"]
    gains, visible_voxels = np.empty(len(state["candidates"])), state["visible_voxels"]
    for c, view in enumerate(state["candidates"]):
        reached = visible_voxels(c)
        p = world.probability(reached["centres"])
        unknown = (p >= free) & (p <= occupied)
        distance = np.linalg.norm(reached["centres"] - state["viewspace"][view][:3, 3], axis=1)
        gains[c] = np.sum(reached["visibility"][unknown] / np.maximum(distance[unknown], 1e-3))
    return gains


def pc_through_the_state(state):
    """The built-in Proximity Count, asked for through the state: the pc run again."""
    return state["metric_values"]("pc")[:, 0]


def main():
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--model", default="bunny")
    parser.add_argument("--seeds", type=int, nargs="+", default=[0, 1])
    parser.add_argument("--iterations", type=int, default=6, help="scans per run (at least 4)")
    args = parser.parse_args()
    if args.iterations < 4:
        parser.error("--iterations must be at least 4 (the table reports coverage after 4 scans)")

    planners = [("pc (built-in)", "pc"), ("pc through the state", pc_through_the_state),
                ("unknown / distance (this file)", unknown_by_distance)]
    print(f"{args.model}, seeds {args.seeds}, {args.iterations} scans, released rays")
    print(f"{'planner':32s} {'cov@2':>6s} {'cov@4':>6s} {'cov AUC':>8s} {'s/decision':>11s}")
    runs = {}
    for label, planner in planners:
        results = [nbv.reconstruct(args.model, metric=planner, seed=seed, iterations=args.iterations)
                   for seed in args.seeds]
        runs[label] = results
        coverage = np.array([[it["coverage"] for it in r["iterations"]] for r in results])
        seconds = [it["seconds_ig"] for r in results for it in r["iterations"][:-1]]
        print(f"{label:32s} {coverage[:, 1].mean():6.3f} {coverage[:, 3].mean():6.3f} "
              f"{np.mean([r['auc_coverage'] for r in results]):8.4f} {np.mean(seconds):11.4f}")
    same = all([it["view"] for it in a["iterations"]] == [it["view"] for it in b["iterations"]]
               for a, b in zip(runs["pc (built-in)"], runs["pc through the state"]))
    print("pc through the state is the pc run" if same else "pc through the state chose other views than pc")
    return 0 if same else 1


if __name__ == "__main__":
    sys.exit(main())
