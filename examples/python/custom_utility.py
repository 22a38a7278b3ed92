#!/usr/bin/python3
"""A utility of your own over the evaluator's table: gain per metre travelled.

The planner's Eq. 12 trades gain against travel with a weight gamma. Here the table's columns
are combined in numpy instead: Proximity Count and Rear Side Entropy, each normalised by its
sum over the candidates, averaged, then divided by (1 + the distance to travel). The view this
picks is compared with the one the plain metric picks.

    PYTHONPATH=build/python /usr/bin/python3 examples/python/custom_utility.py
"""
import numpy as np

import nbv


def main():
    mesh = nbv.load_mesh("bunny")
    views = nbv.dome48()
    world = nbv.OccupancyMap()
    current = 0
    for index in (current, 16, 33):
        _, points = nbv.DepthCamera().render(mesh, views[index])
        world.integrate(points, views[index][:3, 3])
    current = 33  # the sensor is at the last view it scanned

    candidates = np.array([v for v in range(len(views)) if v not in (0, 16, 33)])
    table = nbv.Decider().evaluate(world, views[candidates], nbv.ray_set("released"), metrics=("pc", "rse"))
    shares = table.values / table.values.sum(axis=0)        # each metric as a share of its total
    gain = shares.mean(axis=1)
    travel = np.linalg.norm(views[candidates][:, :3, 3] - views[current][:3, 3], axis=1)
    utility = gain / (1.0 + travel)

    plain = candidates[int(np.argmax(table["pc"]))]
    mine = candidates[int(np.argmax(utility))]
    print(f"pc alone picks view {plain} ({travel[candidates == plain][0]:.2f} m away)")
    print(f"(pc + rse) per metre picks view {mine} ({travel[candidates == mine][0]:.2f} m away)")
    for rank, i in enumerate(np.argsort(-utility)[:5], start=1):
        print(f"  {rank}. view {candidates[i]:2d}: pc share {shares[i, 0]:.4f}, rse share {shares[i, 1]:.4f}, "
              f"travel {travel[i]:.2f} m, utility {utility[i]:.5f}")


if __name__ == "__main__":
    main()
