#!/usr/bin/python3
"""Score 1,000 candidate views on a sphere around a partly scanned object and print the best.

The object is scanned from two views of the paper's dome; then 1,000 views on a Fibonacci
sphere around it are scored by Proximity Count and Occlusion Aware with
the released ray set, and the best of each is printed.

    PYTHONPATH=build/python /usr/bin/python3 examples/python/score_sphere.py [--model bunny]
"""
import argparse
import time

import numpy as np

import nbv


def main():
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--model", default="bunny", help="a standard model or a mesh file")
    parser.add_argument("--count", type=int, default=1000, help="views on the sphere")
    args = parser.parse_args()

    mesh = nbv.load_mesh(args.model)
    camera = nbv.DepthCamera()
    dome = nbv.dome48()
    world = nbv.OccupancyMap(resolution=0.01)
    for index in (0, 24):  # two scans: the side at azimuth 0, then the top at azimuth 180 degrees
        _, points = camera.render(mesh, dome[index])
        world.integrate(points, dome[index][:3, 3])

    lo, hi = mesh.bounds
    centre = (lo + hi) / 2.0
    views = nbv.fibonacci_sphere(args.count, radius=0.6, target=centre)  # min_z=0.0: none below the base
    start = time.perf_counter()
    table = nbv.Decider().evaluate(world, views, nbv.ray_set("released"), metrics=("pc", "oa"))
    seconds = time.perf_counter() - start
    print(f"{args.model}: {world.counts()['measured']} measured voxels; {len(views)} views on a 0.6 m sphere "
          f"scored in {seconds:.3f} s ({table.rays} rays)")
    for metric in table.metrics:
        column = table[metric]
        best = int(np.argmax(column))
        x, y, z = views[best][:3, 3]
        print(f"best by {metric}: view {best} at ({x:.3f}, {y:.3f}, {z:.3f}) m, gain {column[best]:.6g} "
              f"({column[best] / np.median(column):.2f}x the median)")


if __name__ == "__main__":
    main()
