#!/usr/bin/python3
"""The next-best-view loop written in Python: render, integrate, evaluate, choose.

It runs the paper's Algorithm 1 step by step with the package's parts, then checks that it
visited the same views, with the same coverage, as nbv.reconstruct (and `nbv reconstruct`) for
the same seed. Exits 1 if they differ.

    PYTHONPATH=build/python /usr/bin/python3 examples/python/reconstruction_loop.py [--seed 0]
"""
import argparse
import sys

import numpy as np

import nbv


def main():
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--model", default="bunny")
    parser.add_argument("--metric", default="pc", help="one metric's short name")
    parser.add_argument("--seed", type=int, default=0)
    parser.add_argument("--iterations", type=int, default=10)
    args = parser.parse_args()

    mesh = nbv.load_mesh(args.model)
    camera = nbv.DepthCamera()
    views = nbv.dome48()
    rays = nbv.ray_set("released")
    world = nbv.OccupancyMap(resolution=0.01)
    evaluator = nbv.Decider()
    coverage = nbv.SurfaceCoverage(nbv.sample_surface(mesh))  # 200,000 points, seed 0, as reconstruct's
    visited = []
    view = nbv.start_view(args.seed, len(views))
    for iteration in range(1, args.iterations + 1):
        visited.append(view)
        _, points = camera.render(mesh, views[view])              # scan
        world.integrate(points, views[view][:3, 3])                # integrate from the camera's position
        coverage.add_scan(points)
        print(f"{iteration:4d} view {view:2d}  coverage {coverage.coverage:.4f}")
        if iteration == args.iterations:
            break
        candidates = [v for v in range(len(views)) if v not in visited]
        table = evaluator.evaluate(world, views[candidates], rays, metrics=(args.metric,))
        view = candidates[int(np.argmax(table[args.metric]))]     # Eq. 13, gamma 0: the first of ties

    reference = nbv.reconstruct(args.model, metric=args.metric, seed=args.seed, iterations=args.iterations)
    same = visited == [it["view"] for it in reference["iterations"]]
    same_coverage = coverage.coverage == reference["iterations"][-1]["coverage"]
    print(f"same views as nbv.reconstruct: {same}; the same final coverage: {same_coverage}")
    return 0 if same and same_coverage else 1


if __name__ == "__main__":
    sys.exit(main())
