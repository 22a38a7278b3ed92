#!/usr/bin/python3
"""A volumetric information of your own, in numpy, benchmarked against the built-in ones.

The paper's formulations add up a voxel's information along every ray that crosses it, so the
voxels near the camera, which many rays cross, count many times. The formulation here counts
each voxel a view's rays reach once, with the greatest visibility any ray reaches it with:

    I(view) = sum over the voxels x the view's rays reach of  P_v(x) * H(P_o(x))

(P_v: Eq. 5; H: the entropy of the voxel's occupancy probability, in bits), computed from
Decider.visible_voxels and OccupancyMap.probability. The paper's NBV loop runs with it and
with two built-in metrics, oa (Eq. 6: the same terms, summed per ray) and pc, for each seed;
the table gives surface coverage after 2, 4 and 6 scans, its AUC and the seconds per decision,
as means over the seeds. The built-in runs are checked against nbv.reconstruct (the same views
and AUC); the example exits 1 if they differ.

    PYTHONPATH=build/python /usr/bin/python3 examples/python/own_formulation.py [--seeds 0 1] [--iterations 8]
"""
import argparse
import sys
import time

import numpy as np

import nbv


def entropy_bits(p):
    """H(p) in bits of occupancy probabilities p (0.5 for a voxel never measured: 1 bit)."""
    p = np.clip(p, 1e-12, 1.0 - 1e-12)
    return -(p * np.log2(p) + (1.0 - p) * np.log2(1.0 - p))


def entropy_once(world, evaluator, views, rays):
    """The formulation of this example: each reached voxel's entropy once, times its visibility."""
    gains = np.empty(len(views))
    for i, view in enumerate(views):
        reached = evaluator.visible_voxels(world, view, rays)
        gains[i] = np.sum(reached["visibility"] * entropy_bits(world.probability(reached["centres"])))
    return gains


def built_in(metric):
    """A built-in metric's gains, one evaluator call for every candidate."""
    def gains(world, evaluator, views, rays):
        return evaluator.evaluate(world, views, rays, metrics=(metric,))[metric]
    return gains


def coverage_auc(curve):
    """The trapezoidal rule over scans 0..N, coverage 0 at scan 0, as nbv.reconstruct's auc_coverage."""
    return (sum(curve) - 0.5 * curve[-1]) / len(curve)


def run(mesh, surface, gain, seed, iterations):
    """The paper's loop (gamma 0): scan, integrate, move to the unvisited view of greatest gain."""
    camera, views, rays = nbv.DepthCamera(), nbv.dome48(), nbv.ray_set("released")
    world, evaluator = nbv.OccupancyMap(), nbv.Decider()
    coverage = nbv.SurfaceCoverage(surface)
    visited, curve, seconds = [], [], []
    view = nbv.start_view(seed, len(views))
    for iteration in range(1, iterations + 1):
        visited.append(view)
        _, points = camera.render(mesh, views[view])
        world.integrate(points, views[view][:3, 3])
        coverage.add_scan(points)
        curve.append(coverage.coverage)
        if iteration == iterations:
            break
        candidates = [v for v in range(len(views)) if v not in visited]
        start = time.perf_counter()
        gains = gain(world, evaluator, views[candidates], rays)
        seconds.append(time.perf_counter() - start)
        view = candidates[int(np.argmax(gains))]  # the first of ties, as nbv.reconstruct
    return visited, curve, seconds


def main():
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--model", default="bunny")
    parser.add_argument("--seeds", type=int, nargs="+", default=[0, 1])
    parser.add_argument("--iterations", type=int, default=8, help="scans per run (at least 6)")
    args = parser.parse_args()
    if args.iterations < 6:
        parser.error("--iterations must be at least 6 (the table reports coverage after 6 scans)")

    mesh = nbv.load_mesh(args.model)
    surface = nbv.sample_surface(mesh)  # 200,000 points, seed 0, as nbv.reconstruct's
    formulations = [("oa (built-in)", built_in("oa"), "oa"), ("pc (built-in)", built_in("pc"), "pc"),
                    ("entropy once (this file)", entropy_once, None)]
    print(f"{args.model}, seeds {args.seeds}, {args.iterations} scans, released rays")
    print(f"{'formulation':26s} {'cov@2':>6s} {'cov@4':>6s} {'cov@6':>6s} {'cov AUC':>8s} {'s/decision':>11s}")
    same = True
    for label, gain, metric in formulations:
        curves, seconds = [], []
        for seed in args.seeds:
            visited, curve, spent = run(mesh, surface, gain, seed, args.iterations)
            curves.append(curve)
            seconds.extend(spent)
            if metric is not None:
                reference = nbv.reconstruct(args.model, metric=metric, seed=seed, iterations=args.iterations)
                if visited != [it["view"] for it in reference["iterations"]] or \
                        not np.isclose(coverage_auc(curve), reference["auc_coverage"], rtol=0.0, atol=1e-12):
                    print(f"{label}, seed {seed}: not the views or AUC of nbv.reconstruct", file=sys.stderr)
                    same = False
        curves = np.array(curves)
        aucs = [coverage_auc(list(c)) for c in curves]
        print(f"{label:26s} {curves[:, 1].mean():6.3f} {curves[:, 3].mean():6.3f} {curves[:, 5].mean():6.3f} "
              f"{np.mean(aucs):8.4f} {np.mean(seconds):11.4f}")
    print("the built-in runs are those of nbv.reconstruct" if same else "the built-in runs differ from nbv.reconstruct")
    return 0 if same else 1


if __name__ == "__main__":
    sys.exit(main())
