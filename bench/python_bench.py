#!/usr/bin/python3
"""The Python package's costs, measured side by side in one run (docs/performance-log.md, "Python").

1. Overhead per call: nbv.Decider.evaluate on the bunny-3 map, 48 dome views, the released
   ray set, every metric; the wall time of the Python call against the seconds the C++
   evaluation inside it took (IgTable.seconds), per call, median over many calls; and the part
   of it the argument check takes (nbv/_arguments.py): the call against the compiled function
   it makes, interleaved.
2. Two Python threads, two evaluators, one TBB thread each: wall time against the same two
   evaluations one after the other (the GIL is released while the rays are walked).
3. The visible voxels of a path of three views: one visible_voxels call with the (3, 4, 4)
   poses against three calls merged in numpy (np.unique, np.maximum.at, np.add.at), the same
   voxels, at 1 and 2 threads.
4. An experiment (the bunny, every metric, 3 seeds, 10 scans): one experiment() call, its runs
   side by side sharing the model's scene, ground truth and scans, against a loop of
   reconstruct() calls (each on every core), the same views; --experiments rounds, alternating.

    PYTHONPATH=build/python /usr/bin/python3 bench/python_bench.py [--calls 300] [--experiments 1]
"""
import argparse
import statistics
import threading
import time

import numpy as np

import nbv


def bunny3():
    mesh = nbv.load_mesh("bunny")
    camera = nbv.DepthCamera()
    views = nbv.dome48()
    world = nbv.OccupancyMap()
    for index in (0, 16, 33):
        _, points = camera.render(mesh, views[index])
        world.integrate(points, views[index][:3, 3])
    return world, views


def overhead(world, views, calls):
    rays = nbv.ray_set("released")
    evaluator = nbv.Decider()
    evaluator.evaluate(world, views, rays, metrics="all")  # the snapshot and the ray order, once
    walls, insides = [], []
    for _ in range(calls):
        start = time.perf_counter()
        table = evaluator.evaluate(world, views, rays, metrics="all")
        walls.append(time.perf_counter() - start)
        insides.append(table.seconds)
    wall, inside = statistics.median(walls), statistics.median(insides)
    extra = statistics.median(w - s for w, s in zip(walls, insides))
    print(f"released rays, 48 views, all metrics, {calls} calls: Python call {wall * 1e3:.3f} ms, "
          f"C++ evaluation {inside * 1e3:.3f} ms, overhead {extra * 1e6:.1f} us per call ({extra / inside:.1%})")
    # The argument check's part: the overhead of the call against that of the compiled function
    # it makes (__wrapped__), given the arguments the check converts to, interleaved.
    compiled = nbv.Decider.evaluate.__wrapped__
    checked, direct = [], []
    for _ in range(calls):
        start = time.perf_counter()
        table = evaluator.evaluate(world, views, rays, metrics="all")
        checked.append(time.perf_counter() - start - table.seconds)
        start = time.perf_counter()
        table = compiled(evaluator, world, views, rays, ["all"], "paper", 1.5, None, False, 0, None)
        direct.append(time.perf_counter() - start - table.seconds)
    with_check, without = statistics.median(checked), statistics.median(direct)
    print(f"  of which the argument check: {(with_check - without) * 1e6:.1f} us (overhead {with_check * 1e6:.1f} us "
          f"checked, {without * 1e6:.1f} us calling the compiled function itself)")


def two_threads(world, views, rounds):
    rays = nbv.ray_set(4)  # 22,560 rays per view: enough work to see two cores
    evaluators = [nbv.Decider(), nbv.Decider()]
    for e in evaluators:
        e.evaluate(world, views, rays, metrics="all", threads=1)

    def one(i):
        evaluators[i].evaluate(world, views, rays, metrics="all", threads=1)

    serial, parallel = [], []
    for _ in range(rounds):
        start = time.perf_counter()
        one(0)
        one(1)
        serial.append(time.perf_counter() - start)
        threads = [threading.Thread(target=one, args=(i,)) for i in range(2)]
        start = time.perf_counter()
        for t in threads:
            t.start()
        for t in threads:
            t.join()
        parallel.append(time.perf_counter() - start)
    s, p = statistics.median(serial), statistics.median(parallel)
    print(f"two evaluations (stride-4 rays, 48 views, 1 TBB thread each), median of {rounds}: one after the other "
          f"{s:.3f} s, in two Python threads {p:.3f} s ({s / p:.2f}x)")


def merged_in_numpy(parts):
    """The voxels of several visible_voxels results, each once: index, greatest visibility, rays."""
    index = np.concatenate([p["index"] for p in parts])
    unique, inverse = np.unique(index[:, ::-1], axis=0, return_inverse=True)  # ordered by z, y, x
    inverse = inverse.ravel()
    best = np.zeros(len(unique))
    np.maximum.at(best, inverse, np.concatenate([p["visibility"] for p in parts]))
    rays = np.zeros(len(unique), np.uint64)
    np.add.at(rays, inverse, np.concatenate([p["rays"] for p in parts]).astype(np.uint64))
    return unique[:, ::-1], best, rays


def path_voxels(world, views, rounds):
    rays = nbv.ray_set("released")
    path = views[[3, 4, 5]]
    evaluator = nbv.Decider()
    together = evaluator.visible_voxels(world, path, rays)
    index, best, count = merged_in_numpy([evaluator.visible_voxels(world, v, rays) for v in path])
    assert (together["index"] == index).all() and (together["visibility"] == best).all() and \
        (together["rays"] == count).all()
    for threads in (1, 2):
        one, three = [], []
        for _ in range(rounds):
            start = time.perf_counter()
            evaluator.visible_voxels(world, path, rays, threads=threads)
            one.append(time.perf_counter() - start)
            start = time.perf_counter()
            merged_in_numpy([evaluator.visible_voxels(world, v, rays, threads=threads) for v in path])
            three.append(time.perf_counter() - start)
        a, b = statistics.median(one), statistics.median(three)
        print(f"visible voxels of a path of 3 views ({len(index)} voxels), released rays, {threads} thread(s), "
              f"median of {rounds}: one call {a * 1e3:.1f} ms, three calls merged in numpy {b * 1e3:.1f} ms")


def experiment_against_a_loop(rounds):
    metrics = list(nbv.METRICS)
    for _ in range(rounds):
        start = time.perf_counter()
        runs = nbv.experiment("bunny", metrics=metrics, trials=3, iterations=10)
        together = time.perf_counter() - start
        start = time.perf_counter()
        loop = [nbv.reconstruct("bunny", metric=m, seed=s, iterations=10) for m in metrics for s in range(3)]
        one_by_one = time.perf_counter() - start
        assert [[it["view"] for it in r["iterations"]] for r in runs] == \
            [[it["view"] for it in r["iterations"]] for r in loop]
        print(f"experiment of {len(runs)} runs (bunny, 9 metrics x 3 seeds, 10 scans): experiment() {together:.1f} s, "
              f"a loop of reconstruct() {one_by_one:.1f} s ({one_by_one / together:.2f}x)")


def main():
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--calls", type=int, default=300)
    parser.add_argument("--rounds", type=int, default=5)
    parser.add_argument("--experiments", type=int, default=1, help="rounds of part 4 (0: skip it)")
    args = parser.parse_args()
    world, views = bunny3()
    print(f"nbv {nbv.__version__}, ray walks {nbv.isa}")
    overhead(world, views, args.calls)
    two_threads(world, views, args.rounds)
    path_voxels(world, views, 4 * args.rounds)
    experiment_against_a_loop(args.experiments)


if __name__ == "__main__":
    main()
