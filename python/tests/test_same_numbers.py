"""The Python package gives the command line's numbers: evaluations, maps and reconstructions."""
import csv
import json
import math

import numpy as np
import pytest

import nbv
from conftest import run_cli


def read_csv(path):
    with open(path, newline="") as f:
        rows = list(csv.reader(f))
    return rows[0][1:], np.array([[float(x) for x in row[1:]] for row in rows[1:]])


@pytest.mark.parametrize("visibility", ["paper", "released"])
def test_evaluation_equals_nbv_evaluate(bunny3, tmp_path, visibility):
    world, path = bunny3
    csv_path = tmp_path / "ig.csv"
    run_cli("evaluate", "--map", path, "--views", "dome48", "--metrics", "all", "--rays", "released",
            "--visibility", visibility, "--csv", csv_path)
    names, expected = read_csv(csv_path)
    table = nbv.Decider().evaluate(world, nbv.dome48(), nbv.ray_set("released"), metrics="all",
                                       visibility=visibility)
    assert table.metrics == names
    assert table.values.shape == (48, len(nbv.METRICS))
    np.testing.assert_array_equal(table.values, expected)  # the CSV holds every bit (%.17g)
    assert table.rays == 48 * 950


def test_map_built_in_python_equals_the_workload(bunny3):
    world, _ = bunny3
    mesh = nbv.load_mesh("bunny")
    camera = nbv.DepthCamera()
    views = nbv.dome48()
    built = nbv.OccupancyMap(resolution=0.01)
    for index in (0, 16, 33):  # the workload's scans, full image
        depth, points = camera.render(mesh, views[index])
        assert depth.shape == (480, 752) and depth.dtype == np.float32
        assert points.dtype == np.float32 and points.shape == (int((depth > 0).sum()), 3)
        built.integrate(points, views[index][:3, 3])
    assert built.counts() == world.counts()
    for mine, theirs in zip(built.measured_voxels(), world.measured_voxels()):
        np.testing.assert_array_equal(mine, theirs)
    for mine, theirs in zip(built.proximity_marks(), world.proximity_marks()):
        np.testing.assert_array_equal(mine, theirs)


@pytest.mark.parametrize("cli_scene, scene", [
    ((), {}),
    (("--scene", "released", "--up", "y", "--no-return", "clear"), {"scene": "released", "up": "y", "no_return": "clear"}),
    (("--scene", "paper", "--crop", "-0.5", "0.5", "-0.5", "0.5", "0", "0.6"),
     {"scene": "paper", "crop": (-0.5, 0.5, -0.5, 0.5, 0, 0.6)}),
    (("--gamma", "0.25", "--max-ray-depth", "1.2", "--g-thresh", "none"), {"gamma": 0.25, "max_ray_depth": 1.2,
                                                                          "g_thresh": None}),
])
def test_reconstruct_saved_is_the_file_of_nbv_reconstruct(tmp_path, cli_scene, scene):
    """save_run() writes what `nbv reconstruct --json` writes: the same JSON, field for field."""
    run_cli("reconstruct", "--model", "bunny", "--metric", "0.5*pc+0.5*vg", "--iterations", "5", "--seed", "3",
            "--threads", "1", "--no-timings", "--json", tmp_path / "cli.json", *cli_scene)
    seen = []
    result = nbv.reconstruct("bunny", metric="0.5*pc+0.5*vg", seed=3, iterations=5, threads=1, no_timings=True,
                             callback=lambda record: seen.append(record["view"]), **scene)
    assert [it["view"] for it in result["iterations"]] == seen
    nbv.save_run(result, tmp_path / "python.json")
    with open(tmp_path / "cli.json") as a, open(tmp_path / "python.json") as b:
        expected, saved = json.load(a), json.load(b)
    assert list(saved) == list(expected)
    assert saved == expected
    assert [list(it) for it in saved["iterations"]] == [list(it) for it in expected["iterations"]]
    # load_run() reads the CLI's file back as reconstruct() returned the run: NaN for null, arrays.
    assert_same_run(nbv.load_run(tmp_path / "cli.json"), result)
    nbv.save_run(nbv.load_run(tmp_path / "cli.json"), tmp_path / "again.json")
    with open(tmp_path / "again.json") as f:
        assert json.load(f) == expected


def assert_same_run(a, b, where="run"):
    """a == b, a tuple equal to a list, NaN equal to NaN, arrays of the same dtype and values."""
    if isinstance(a, np.ndarray) or isinstance(b, np.ndarray):
        assert isinstance(a, np.ndarray) and isinstance(b, np.ndarray) and a.dtype == b.dtype, where
        np.testing.assert_array_equal(a, b, err_msg=where)
    elif isinstance(a, dict):
        assert isinstance(b, dict) and list(a) == list(b), where
        for key in a:
            assert_same_run(a[key], b[key], f"{where}[{key!r}]")
    elif isinstance(a, (list, tuple)):
        assert isinstance(b, (list, tuple)) and len(a) == len(b), where
        for i, (x, y) in enumerate(zip(a, b)):
            assert_same_run(x, y, f"{where}[{i}]")
    elif isinstance(a, float) and math.isnan(a):
        assert isinstance(b, float) and math.isnan(b), where
    else:
        assert type(a) is type(b) and a == b, where


def test_a_saved_run_draws_the_report_of_nbv_reconstruct(tmp_path):
    """`nbv report` on save_run()'s file draws the page `nbv reconstruct --html` draws."""
    run_cli("reconstruct", "--model", "bunny", "--iterations", "3", "--seed", "1", "--scene", "paper", "--no-timings",
            "--html", tmp_path / "cli.html")
    nbv.save_run(nbv.reconstruct("bunny", iterations=3, seed=1, scene="paper", no_timings=True), tmp_path / "run.json")
    run_cli("report", tmp_path / "run.json", "--html", tmp_path / "python.html")
    assert (tmp_path / "python.html").read_bytes() == (tmp_path / "cli.html").read_bytes()


def test_max_seconds_stops_the_run_and_every_option_is_a_field(tmp_path):
    result = nbv.reconstruct("bunny", iterations=5, seed=1, max_seconds=1e-9)
    assert result["stop"] == "max_seconds" and len(result["iterations"]) == 1
    assert [result[k] for k in ("gamma", "g_thresh", "max_ray_depth", "max_seconds")] == [0.0, None, 1.5, 1e-9]
    with pytest.raises(nbv.InvalidArgument, match=r"invalid reconstruction option: max_seconds = -1 \(must be finite and > 0\)"):
        nbv.reconstruct("bunny", iterations=2, max_seconds=-1)
    # A run file written before an option existed reads its default.
    nbv.save_run(nbv.reconstruct("bunny", iterations=2, seed=1, no_timings=True), tmp_path / "run.json")
    with open(tmp_path / "run.json") as f:
        old = json.load(f)
    del old["max_seconds"], old["max_ray_depth"], old["g_thresh"]
    with open(tmp_path / "old.json", "w") as f:
        json.dump(old, f)
    loaded = nbv.load_run(tmp_path / "old.json")
    assert (loaded["g_thresh"], loaded["max_ray_depth"], loaded["max_seconds"]) == (None, 1.5, None)


def test_the_oracle_is_a_planner_of_reconstruct_and_experiment(tmp_path):
    """metric="oracle" plans by the ground truth: each next view adds the most coverage, the
    gain it promised; `nbv reconstruct --metric oracle` is the same run."""
    run_cli("reconstruct", "--model", "bunny", "--metric", "oracle", "--iterations", "4", "--seed", "3", "--no-timings",
            "--json", tmp_path / "cli.json")
    result = nbv.reconstruct("bunny", metric="oracle", iterations=4, seed=3, no_timings=True)
    nbv.save_run(result, tmp_path / "python.json")
    with open(tmp_path / "cli.json") as a, open(tmp_path / "python.json") as b:
        assert json.load(a) == json.load(b)
    its = result["iterations"]
    for before, after in zip(its, its[1:]):
        gains = before["gains"]
        assert after["view"] == int(np.nanargmax(gains)) and before["rays"] == 0
        assert after["coverage"] - before["coverage"] == pytest.approx(np.nanmax(gains), abs=1e-12)
    runs = nbv.experiment("bunny", metrics="pc,oracle", trials=1, iterations=4, no_timings=True)
    assert [r["metric"] for r in runs] == ["pc", "oracle"]
    assert runs[1]["iterations"][1]["coverage"] >= runs[0]["iterations"][1]["coverage"]
    with pytest.raises(nbv.InvalidArgument, match="oracle takes no anytime decision"):
        nbv.reconstruct("bunny", metric="oracle", anytime=True)


def test_a_planner_of_ones_own_is_a_callable_given_as_the_metric():
    """metric=callable: nbv's loop calls it with the state; pc's own values through the state
    are the pc run; its label is the function's name; errors reach the caller."""
    seen = []

    def pc_again(state):
        seen.append(state)
        assert len(state["taken"]) == state["iteration"] and state["viewspace"].shape == (48, 4, 4)
        assert sorted(set(range(48)) - set(state["taken"])) == list(state["candidates"])
        reached = state["visible_voxels"](0)
        assert reached["centres"].shape[0] == reached["visibility"].shape[0] > 0
        return state["metric_values"]("pc")[:, 0]

    pc = nbv.reconstruct("bunny", metric="pc", iterations=4, seed=1, no_timings=True)
    mine = nbv.reconstruct("bunny", metric=pc_again, iterations=4, seed=1, no_timings=True)
    assert mine["metric"] == "pc_again" and len(seen) == 3
    assert [it["view"] for it in mine["iterations"]] == [it["view"] for it in pc["iterations"]]
    np.testing.assert_array_equal(mine["iterations"][0]["gains"], pc["iterations"][0]["gains"])
    assert mine["iterations"][0]["rays"] > pc["iterations"][0]["rays"]  # pc's rays and candidate 0's
    with pytest.raises(nbv.InvalidArgument, match="decision it belongs to is over"):
        seen[0]["metric_values"]("pc")
    with pytest.raises(ZeroDivisionError):
        nbv.reconstruct("bunny", metric=lambda state: 1 / 0, iterations=2)
    with pytest.raises(nbv.InvalidArgument, match="the planner gave 1 gains for 47 candidates"):
        nbv.reconstruct("bunny", metric=lambda state: [1.0], iterations=2)
    with pytest.raises(nbv.InvalidArgument, match="not a finite number"):
        nbv.reconstruct("bunny", metric=lambda state: np.full(len(state["candidates"]), np.nan), iterations=2)
    with pytest.raises(nbv.InvalidArgument, match="not a sequence of numbers"):
        nbv.reconstruct("bunny", metric=lambda state: "high", iterations=2)
    with pytest.raises(nbv.InvalidArgument, match="reconstruct: metric = 5 is not"):
        nbv.reconstruct("bunny", metric=5)
    # In an experiment, beside the built-in metrics: labelled by name, runs side by side.
    runs = nbv.experiment("bunny", metrics=["pc", pc_again], trials=2, iterations=3, no_timings=True, threads=2)
    assert [(r["metric"], r["seed"]) for r in runs] == [("pc", 0), ("pc", 1), ("pc_again", 0), ("pc_again", 1)]
    for a, b in zip(runs[:2], runs[2:]):
        assert [it["view"] for it in a["iterations"]] == [it["view"] for it in b["iterations"]]
    assert "pc_again" in nbv.table1(runs)

    def broken(state):
        raise KeyError("from the planner")
    with pytest.raises(KeyError, match="from the planner"):
        nbv.experiment("bunny", metrics=[broken], trials=2, iterations=3, threads=2)
    with pytest.raises(nbv.InvalidArgument, match="'pc_again' is given twice"):
        nbv.experiment("bunny", metrics=[pc_again, pc_again], trials=1, iterations=2)


def test_a_callback_stops_the_run():
    result = nbv.reconstruct("bunny", iterations=6, seed=1, callback=lambda record: record["iteration"] < 2)
    assert result["stop"] == "caller" and len(result["iterations"]) == 2


def test_a_callback_error_reaches_the_caller():
    def broken(record):
        raise KeyError("from the callback")

    with pytest.raises(KeyError, match="from the callback"):
        nbv.reconstruct("bunny", iterations=3, callback=broken)


def test_an_experiment_is_its_reconstructions_whatever_the_threads():
    """Each run of experiment() is the dict reconstruct() returns for its model, metric and seed;
    a model's runs share its scene, and the list is the same at 1 and 2 threads."""
    mesh = nbv.load_mesh("dragon")
    models = {"bunny": "bunny", "dragon-mesh": mesh}
    options = dict(trials=2, iterations=3, no_timings=True, weighting="raw")
    runs = nbv.experiment(models, metrics=["pc", "0.5*pc+0.5*vg"], threads=2, **options)
    expected = []
    for label, model in models.items():
        for metric in ("pc", "0.5*pc+0.5*vg"):
            for seed in (0, 1):
                run = nbv.reconstruct(model, metric=metric, seed=seed, iterations=3, no_timings=True,
                                      weighting="raw", threads=1)
                run["model"] = label
                expected.append(run)
    assert_same_run(runs, expected)
    assert_same_run(nbv.experiment(models, metrics="pc,0.5*pc+0.5*vg", threads=1, **options), expected)
    # Trials as seeds: the runs of those seeds, in the order given.
    options["trials"] = (1, 0)
    again = nbv.experiment({"bunny": "bunny"}, metrics="pc", **options)
    assert_same_run(again, [expected[1], expected[0]])


def test_an_experiment_saved_is_the_folder_of_nbv_experiment(tmp_path):
    """save_experiment() writes the results.csv and table.md of `nbv experiment`, byte for byte,
    and `nbv experiment --merge` takes its folder as a shard's."""
    args = ["--models", "bunny,dragon", "--metrics", "oa,pc", "--trials", "2", "--iterations", "3", "--no-timings"]
    run_cli("experiment", *args, "--shard", "1/2", "--out", tmp_path / "cli-1")
    run_cli("experiment", *args, "--out", tmp_path / "cli")
    runs = nbv.experiment("bunny,dragon", metrics=["oa", "pc"], trials=2, iterations=3, no_timings=True)
    nbv.save_experiment(runs, tmp_path / "python")
    for name in ("results.csv", "table.md"):
        assert (tmp_path / "python" / name).read_bytes() == (tmp_path / "cli" / name).read_bytes(), name
    assert nbv.table1(runs) == (tmp_path / "cli" / "table.md").read_text()
    # The other shard, from Python, merged with the command line's first.
    second = nbv.experiment("bunny,dragon", metrics=["oa", "pc"], trials=2, iterations=3, no_timings=True,
                            shard="2/2", out=tmp_path / "python-2")
    assert comparable(second) == comparable(runs[1::2])
    run_cli("experiment", "--merge", tmp_path / "cli-1", tmp_path / "python-2", "--out", tmp_path / "merged")
    for name in ("results.csv", "table.md"):
        assert (tmp_path / "merged" / name).read_bytes() == (tmp_path / "cli" / name).read_bytes(), name
    # Runs saved and loaded one by one give the same table.
    for i, run in enumerate(runs):
        nbv.save_run(run, tmp_path / f"run{i}.json")
    loaded = [nbv.load_run(tmp_path / f"run{i}.json") for i in range(len(runs))]
    assert nbv.table1(loaded[::-1]) == nbv.table1(runs)


def test_a_mesh_file_is_labelled_by_its_stem_as_the_command_line_labels_it(tmp_path):
    """A mesh given by its path is the model "ring" in Python's results as in the command line's
    (Python labelled it "ring.obj", so the two results files did not line up)."""
    corners = [(x, y, z) for x in (-0.05, 0.05) for y in (-0.05, 0.05) for z in (0.0, 0.1)]
    faces = [(1, 2, 4, 3), (5, 7, 8, 6), (1, 5, 6, 2), (3, 4, 8, 7), (1, 3, 7, 5), (2, 6, 8, 4)]
    mesh = tmp_path / "ring.obj"
    mesh.write_text("".join(f"v {x} {y} {z}\n" for x, y, z in corners) +
                    "".join(f"f {a} {b} {c}\nf {a} {c} {d}\n" for a, b, c, d in faces))
    args = ["--metrics", "pc", "--trials", "1", "--iterations", "2", "--no-timings"]
    run_cli("experiment", "--models", mesh, *args, "--out", tmp_path / "cli")
    runs = nbv.experiment(mesh, metrics="pc", trials=1, iterations=2, no_timings=True)
    assert {run["model"] for run in runs} == {"ring"}
    nbv.save_experiment(runs, tmp_path / "python")
    assert (tmp_path / "python" / "results.csv").read_bytes() == (tmp_path / "cli" / "results.csv").read_bytes()


def comparable(value):
    """A run (or a list of runs) with its arrays as lists, NaN as None: == compares it whole."""
    if isinstance(value, np.ndarray):
        return [None if math.isnan(v) else v for v in value.tolist()]
    if isinstance(value, dict):
        return {k: comparable(v) for k, v in value.items()}
    if isinstance(value, (list, tuple)):
        return [comparable(v) for v in value]
    return None if isinstance(value, float) and math.isnan(value) else value


def test_an_experiment_in_a_folder_keeps_its_runs_and_resumes(tmp_path):
    """Stopped after two runs and called again, it runs the rest: the runs and files of one call."""
    sweep = dict(models="bunny", metrics="pc,oa", trials=3, iterations=2, no_timings=True, threads=1)
    whole = nbv.experiment(**sweep, out=tmp_path / "whole")
    ended = []
    part = nbv.experiment(**sweep, out=tmp_path / "part", callback=lambda run: ended.append(run) or len(ended) < 2)
    assert len(part) == 2 and len(list((tmp_path / "part" / "runs").iterdir())) == 2
    assert not (tmp_path / "part" / "results.csv").exists()  # only once every run is there
    again = nbv.experiment(**sweep, out=tmp_path / "part", callback=lambda run: ended.append(run))
    assert comparable(again) == comparable(whole) and len(ended) == 2 + 4  # the kept runs ran once
    for name in ("results.csv", "table.md", "sweep.json"):
        assert (tmp_path / "part" / name).read_bytes() == (tmp_path / "whole" / name).read_bytes(), name
    with pytest.raises(nbv.FileError, match=r'holds another sweep, which only it resumes: metrics \(\["pc"\] against'):
        nbv.experiment(**dict(sweep, metrics="pc"), out=tmp_path / "part")


def test_an_experiments_callback_sees_each_run_and_may_stop_it():
    seen = []
    runs = nbv.experiment("bunny", metrics="pc,oa", trials=2, iterations=2, threads=1,
                          callback=lambda run: seen.append((run["metric"], run["seed"])))
    assert sorted(seen) == sorted((run["metric"], run["seed"]) for run in runs) and len(runs) == 4
    stopped = nbv.experiment("bunny", metrics="pc,oa", trials=2, iterations=2, threads=1, callback=lambda run: False)
    assert [(run["metric"], run["seed"]) for run in stopped] == [("pc", 0)]

    def broken(run):
        raise KeyError("from the callback")

    with pytest.raises(KeyError, match="from the callback"):
        nbv.experiment("bunny", metrics="pc,oa", trials=2, iterations=2, threads=2, callback=broken)


def test_scores_match_the_planner():
    mesh = nbv.load_mesh("bunny")
    truth = nbv.sample_surface(mesh, 20000, seed=0)
    assert truth.shape == (20000, 3)
    assert nbv.surface_coverage(truth, truth) == 1.0
    assert nbv.surface_coverage(truth, truth + np.float32(1.0)) == 0.0
    assert nbv.map_entropy_bits(nbv.OccupancyMap(), (0, 0, 0.15)) == 128**3


def test_decide_equals_nbv_decide(bunny3, tmp_path):
    world, path = bunny3
    json_path = tmp_path / "decision.json"
    run_cli("decide", "--map", path, "--metric", "0.5*pc+0.5*vg", "--rays", "4", "--seed", "5", "--check",
            "--json", json_path)
    with open(json_path) as f:
        expected = json.load(f)
    d = nbv.Decider().decide(world, nbv.dome48(), nbv.ray_set(4), metric="0.5*pc+0.5*vg", seed=5)
    assert d["chosen"] == expected["chosen"] and d["end"] == expected["end"]
    assert d["rays_cast"] == expected["rays_cast"] < d["rays_exhaustive"]
    np.testing.assert_array_equal(d["estimate"], [c["estimate"] for c in expected["candidates"]])
    assert (d["lower"] <= d["estimate"]).all() and (d["estimate"] <= d["upper"]).all()
    exhaustive = np.array([c["exhaustive"] for c in expected["candidates"]])
    assert exhaustive[d["chosen"]] >= (1 - 0.01) * exhaustive.max()  # within epsilon of the best


def test_anytime_reconstruction_equals_nbv_reconstruct_anytime(tmp_path):
    json_path = tmp_path / "run.json"
    run_cli("reconstruct", "--model", "bunny", "--metric", "vg", "--rays", "6", "--iterations", "4", "--seed", "2",
            "--anytime", "--epsilon", "0.02", "--json", json_path)
    with open(json_path) as f:
        expected = json.load(f)
    result = nbv.reconstruct("bunny", metric="vg", rays=6, iterations=4, seed=2, anytime=True, epsilon=0.02)
    assert [it["view"] for it in result["iterations"]] == [it["view"] for it in expected["iterations"]]
    assert [it["rays"] for it in result["iterations"]] == [it["rays"] for it in expected["iterations"]]
    assert expected["anytime"] == result["anytime"] == {"epsilon": 0.02, "delta": 0.01, "budget_ms": None}
    with pytest.raises(nbv.InvalidArgument, match="epsilon needs anytime=True"):
        nbv.reconstruct("bunny", epsilon=0.1)


def test_visible_voxels_are_the_voxels_evaluate_walks(bunny3):
    world, _ = bunny3
    view = nbv.dome48()[5]
    rays = nbv.ray_set("released")
    evaluator = nbv.Decider()
    seen = evaluator.visible_voxels(world, view, rays)
    k = len(seen["visibility"])
    assert seen["index"].shape == (k, 3) and seen["index"].dtype == np.int32
    assert seen["centres"].shape == (k, 3) and seen["rays"].dtype == np.uint32
    assert np.all((seen["visibility"] > 0) & (seen["visibility"] <= 1))
    # Every ray visits a voxel once: the counts add up to the voxels evaluate() walked.
    table = evaluator.evaluate(world, view[None], rays, metrics=("oa",))
    assert int(seen["rays"].sum()) == table.voxels
    # One ray: its voxels' P_v * H is its OA gain (Eq. 6).
    one = rays[400:401]
    voxels = evaluator.visible_voxels(world, view, one)
    p = world.probability(voxels["centres"])
    h = -(p * np.log(p) + (1 - p) * np.log(1 - p))
    oa = evaluator.evaluate(world, view[None], one, metrics=("oa",))["oa"][0]
    assert np.sum(voxels["visibility"] * h) == pytest.approx(oa, rel=1e-9)


def test_visible_voxels_of_a_path_are_its_views_merged(bunny3):
    world, _ = bunny3
    views = nbv.dome48()[[3, 4, 20]]
    rays = nbv.ray_set("released")
    evaluator = nbv.Decider()
    merged, each = {}, 0  # (z, y, x) -> [greatest visibility, rays]
    for view in views:
        part = evaluator.visible_voxels(world, view, rays)
        columns = (part["index"].tolist(), part["visibility"].tolist(), part["rays"].tolist())
        for (x, y, z), visibility, count in zip(*columns):
            entry = merged.setdefault((z, y, x), [0.0, 0])
            entry[0] = max(entry[0], visibility)
            entry[1] += count
            each += 1
    assert len(merged) < each  # the views share voxels
    path = evaluator.visible_voxels(world, views, rays)
    keys = sorted(merged)
    assert path["index"].tolist() == [[x, y, z] for z, y, x in keys]
    assert path["visibility"].tolist() == [merged[k][0] for k in keys]
    assert path["rays"].tolist() == [merged[k][1] for k in keys]
    np.testing.assert_array_equal(path["centres"], (path["index"] + 0.5) * world.resolution)
    with pytest.raises(nbv.InvalidArgument, match=r"^view: no view given \(an empty \(0, 4, 4\) array\)$"):
        evaluator.visible_voxels(world, np.zeros((0, 4, 4)), rays)


def test_visible_voxels_refuse_bad_input(bunny3):
    world, _ = bunny3
    with pytest.raises(nbv.InvalidArgument):
        nbv.Decider().visible_voxels(world, np.eye(3), nbv.ray_set("released"))
    with pytest.raises(nbv.InvalidArgument):
        nbv.Decider().visible_voxels(world, nbv.dome48()[0], np.zeros((0, 3)))
