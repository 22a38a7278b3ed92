"""Bad input raises a Python exception with a clear message, never a crash."""
import json
import re
import subprocess

import numpy as np
import pytest

import nbv
from conftest import run_cli, nbv_cli


@pytest.fixture(scope="module")
def world():
    m = nbv.OccupancyMap()
    m.integrate(np.array([[0.3, 0.0, 0.15]], dtype=np.float32), (0.6, 0.0, 0.15))
    return m


RAYS = nbv.ray_set(8)


def test_exceptions_are_builtin_kinds():
    assert issubclass(nbv.InvalidArgument, ValueError)
    assert issubclass(nbv.CapacityError, MemoryError)
    assert issubclass(nbv.FileError, OSError)
    for sub in (nbv.MapFileError, nbv.CloudFileError, nbv.MeshFileError, nbv.ViewFileError):
        assert issubclass(sub, nbv.FileError)


@pytest.mark.parametrize("points, message", [
    (np.zeros((4, 2), np.float32), r"points: shape \(4, 2\) is not \(N, 3\)"),
    (np.zeros(3, np.float32), r"points: shape \(3,\) is not \(N, 3\)"),
    (np.zeros((4, 3), np.int64), r"points: dtype int64 is not a floating type"),
    (np.array([[0, 0, 0]], dtype=object), r"points: dtype object is not a floating type"),
    ("text", r"points: dtype <U4 is not a floating type"),
])
def test_bad_points(world, points, message):
    with pytest.raises(nbv.InvalidArgument, match=message):
        world.integrate(points, (0, 0, 0))


def test_non_contiguous_points_are_copied_and_give_the_same_map():
    rng = np.random.default_rng(1)
    wide = rng.uniform(-0.3, 0.3, size=(500, 6)).astype(np.float64)
    strided = wide[:, ::2]  # (500, 3), not contiguous
    assert not strided.flags["C_CONTIGUOUS"]
    a, b = nbv.OccupancyMap(), nbv.OccupancyMap()
    a.integrate(strided, (0.6, 0.0, 0.1))
    b.integrate(np.ascontiguousarray(strided, dtype=np.float32), (0.6, 0.0, 0.1))
    for x, y in zip(a.measured_voxels(), b.measured_voxels()):
        np.testing.assert_array_equal(x, y)


@pytest.mark.parametrize("origin, message", [
    ((np.nan, 0.0, 0.0), r"origin: \(nan, 0, 0\) is not finite"),
    ((0.0, 0.0), r"origin: shape \(2,\) is not \(3,\)"),
    (("0", "0", "1"), r"origin: dtype <U1 is not a number type"),
])
def test_bad_origin(world, origin, message):
    with pytest.raises(nbv.InvalidArgument, match=message):
        world.integrate(np.zeros((1, 3), np.float32), origin)


def test_single_points_may_be_integers():
    """A single point may be given in integers; point arrays and poses stay floating."""
    points = np.array([[0.05, 0.0, 0.2], [0.0, 0.05, 0.2]], np.float32)
    floats, integers = nbv.OccupancyMap(), nbv.OccupancyMap()
    floats.integrate(points, (0.0, 0.0, 1.0))
    integers.integrate(points, (0, 0, 1))
    assert len(floats.measured_voxels()[0]) > 0
    for x, y in zip(floats.measured_voxels(), integers.measured_voxels()):
        np.testing.assert_array_equal(x, y)
    np.testing.assert_array_equal(nbv.fibonacci_sphere(5, 1, (0, 0, 0)), nbv.fibonacci_sphere(5, 1.0, (0.0, 0.0, 0.0)))
    centre = np.array([0, 0, 1], np.uint8)
    assert nbv.map_entropy_bits(floats, centre) == nbv.map_entropy_bits(floats, (0.0, 0.0, 1.0))


@pytest.mark.parametrize("call, message", [
    (lambda: nbv.DepthCamera(width=10**10), r"DepthCamera: width = 10000000000 is not an int that fits 32 bits"),
    (lambda: nbv.DepthCamera(width=752.0), r"DepthCamera: width = 752.0 is not an int"),
    (lambda: nbv.DepthCamera(fx="a"), r"DepthCamera: fx = 'a' is not a number"),
    (lambda: nbv.OccupancyMap(p_hit="0.7"), r"OccupancyMap: p_hit = '0.7' is not a number"),
    (lambda: nbv.reconstruct("bunny", iterations=1, crop=5), r"reconstruct: crop = 5 is not a sequence of numbers"),
    (lambda: nbv.reconstruct(5, iterations=1), r"reconstruct: model = 5 is not a model name"),
    (lambda: nbv.reconstruct("bunny", iterations=2, callback=lambda record: "yes"),
     r"reconstruct: the callback's answer = 'yes' is not True or False"),
    (lambda: nbv.ray_set(2**40), r"rays = 1099511627776 is not an int"),
    (lambda: nbv.reconstruct("bunny", seed=-1, iterations=1), r"reconstruct: seed = -1 is not a non-negative int"),
    (lambda: nbv.reconstruct("bunny", iterations=0), r"^reconstruct: iterations = 0 is not a positive int$"),
    (lambda: nbv.reconstruct("bunny", metric=5, iterations=1), r"reconstruct: metric = 5 is not a metric's name, a weighted sum, 'oracle' or a callable"),
    (lambda: nbv.OccupancyMap("0.01"), r"OccupancyMap: resolution = '0.01' is not a number"),
    (lambda: nbv.fibonacci_sphere(-10), r"fibonacci_sphere: count = -10 is not a non-negative int"),
    (lambda: nbv.fibonacci_sphere(10, 0.5, (0, 0, 0), min_z="low"), r"fibonacci_sphere: min_z = 'low' is not None or a number"),
    (lambda: nbv.start_view(-1, 48), r"start_view: seed = -1 is not a non-negative int"),
    (lambda: nbv.surface_coverage(np.zeros((5, 3)), np.zeros((5, 3)), "x"), r"surface_coverage: d_reg = 'x' is not a number"),
    (lambda: nbv.SurfaceCoverage(np.zeros((5, 3)), d_reg=[1]), r"SurfaceCoverage: d_reg = \[1\] is not a number"),
    (lambda: nbv.map_entropy_bits(nbv.OccupancyMap(), (0, 0, 0), edge="big"), r"map_entropy_bits: edge = 'big' is not a number"),
    (lambda: nbv.load_mesh(5), r"load_mesh: name_or_path = 5 is not a model name or a mesh file's path"),
    (lambda: nbv.load_mesh(b"bunny"), r"load_mesh: name_or_path = b'bunny' is not a model name"),
    (lambda: nbv.OccupancyMap().integrate_depth(np.ones((4, 4), np.float32), np.eye(4), "camera"),
     r"OccupancyMap.integrate_depth: camera = 'camera' is not None or an nbv.DepthCamera"),
    (lambda: nbv.OccupancyMap().integrate_depth(np.ones((4, 4), np.float32), nbv.DepthCamera(), np.eye(4)),
     r"OccupancyMap.integrate_depth: T_world_camera is an nbv.DepthCamera: the pose comes second"),
    (lambda: nbv.OccupancyMap().integrate_depth(np.ones((4, 4), np.float32), np.eye(4), None, scale="x"),
     r"OccupancyMap.integrate_depth: scale = 'x' is not a number"),
    (lambda: nbv.OccupancyMap().integrate(np.zeros((0, 3)), (0, 0, 0)), r"^points: the cloud is empty \(0 points\)$"),
    (lambda: nbv.OccupancyMap().integrate(np.full((2, 3), np.nan), (0, 0, 0)), r"^points: none of the 2 points is finite$"),
    (lambda: nbv.Decider().evaluate(nbv.OccupancyMap(), np.zeros((0, 4, 4)), nbv.ray_set()),
     r"^views: no view given \(an empty \(0, 4, 4\) array\)$"),
    (lambda: nbv.reconstruct("bunny", viewspace=np.zeros((0, 4, 4)), iterations=1),
     r"^viewspace: no view given \(an empty \(0, 4, 4\) array\)$"),
    (lambda: nbv.sample_surface(5), r"^sample_surface: mesh = 5 is not a model name, a mesh file or an nbv.Mesh$"),
    (lambda: nbv.DepthCamera().render([1], np.eye(4)), r"^DepthCamera.render: mesh = \[1\] is not a model name"),
    (lambda: nbv.load_map(3), r"^load_map: path = 3 is not a file's path \(a str or an os.PathLike\)$"),
    (lambda: nbv.OccupancyMap().save(None), r"^OccupancyMap.save: path = None is not a file's path"),
    (lambda: nbv.load_views(1.5), r"^load_views: path = 1.5 is not a file's path"),
    (lambda: nbv.save_views(b"x", nbv.dome48()), r"^save_views: path = b'x' is not a file's path"),
])
def test_options_of_the_wrong_type_are_named(call, message):
    """pybind11 alone would say "Unable to cast Python instance to C++ type"."""
    with pytest.raises(nbv.InvalidArgument, match=message):
        call()


@pytest.mark.parametrize("call, message", [
    (lambda: nbv.Decider().evaluate(nbv.OccupancyMap(), nbv.dome48(), RAYS, threads=True),
     r"^Decider.evaluate: threads = True is not None or an int that fits 32 bits$"),
    (lambda: nbv.fibonacci_sphere(10, radius=True), r"^fibonacci_sphere: radius = True is not a number$"),
    (lambda: nbv.DepthCamera().render("bunny", np.eye(4), labels=1), r"^DepthCamera.render: labels = 1 is not True or False$"),
    (lambda: nbv.start_view(2**64, 48), r"^start_view: seed = 18446744073709551616 is not a non-negative int$"),
    (lambda: nbv.ray_set(2.0), r"^ray_set: rays = 2.0 is not 'released', 'released-shipped', 'full' or a pixel stride"),
    (lambda: nbv.reconstruct("bunny", iterations=1, callback=5), r"^reconstruct: callback = 5 is not None or a callable$"),
    (lambda: nbv.Decider().evaluate(nbv.OccupancyMap(), nbv.dome48(), RAYS, metrics=5),
     r"^Decider.evaluate: metrics = 5 is not a metric's name, 'all', a comma-separated list or a sequence of names$"),
    (lambda: nbv.Decider().decide(nbv.OccupancyMap(), nbv.dome48(), RAYS, costs=["far"] * 48),
     r"^Decider.decide: costs = \['far', .* is not None or a sequence of numbers$"),
])
def test_a_bool_is_not_a_number_and_each_kind_names_what_it_takes(call, message):
    """True is an int to Python, but threads=True or labels=1 is a mistake: each kind takes its own type."""
    with pytest.raises(nbv.InvalidArgument, match=message):
        call()


def test_numpy_scalars_and_path_likes_are_taken(tmp_path):
    views = nbv.fibonacci_sphere(np.int32(6), np.float32(0.5), (0, 0, 0.2), min_z=np.float64(0.0))
    assert len(views) == len(nbv.fibonacci_sphere(6, 0.5, (0, 0, 0.2), min_z=0.0))
    nbv.save_views(tmp_path / "views.txt", views)
    run = nbv.reconstruct("bunny", iterations=1, viewspace=tmp_path / "views.txt", seed=np.uint64(2))
    assert run["viewspace"] == str(tmp_path / "views.txt") and run["seed"] == 2


@pytest.mark.parametrize("build", [
    lambda: nbv.OccupancyMap(p_hit="x"),  # refused by the argument check
    lambda: nbv.OccupancyMap(resolution=1e-5),  # refused by the compiled constructor
    lambda: nbv.OccupancyMap(0.01, 0.02),  # Python's TypeError: one positional parameter
])
def test_a_refused_constructor_leaves_no_unbuilt_instance_in_its_traceback(build):
    """A traceback printer that shows each frame's arguments (pytest's does) must not meet the
    instance a constructor did not build: a method of it would read memory never written."""
    with pytest.raises((nbv.InvalidArgument, TypeError)) as error:
        build()
    frame = error.value.__traceback__
    while frame is not None:
        assert not any(isinstance(v, nbv.OccupancyMap) or (isinstance(v, tuple) and any(isinstance(x, nbv.OccupancyMap) for x in v))
                       for v in frame.tb_frame.f_locals.values()), frame.tb_frame.f_code.co_name
        frame = frame.tb_next


@pytest.mark.parametrize("method, keywords, message", [
    ("evaluate", {"threads": "2"}, r"Decider.evaluate: threads = '2' is not None or an int that fits 32 bits"),
    ("evaluate", {"max_ray_depth": "1"}, r"Decider.evaluate: max_ray_depth = '1' is not a number"),
    ("evaluate", {"seed": -3}, r"Decider.evaluate: seed = -3 is not a non-negative int"),
    ("evaluate", {"isa": 2}, r"Decider.evaluate: isa = 2 is not None or a string"),
    ("decide", {"epsilon": "a"}, r"Decider.decide: epsilon = 'a' is not a number"),
    ("decide", {"max_rays": -1}, r"Decider.decide: max_rays = -1 is not None or a non-negative int"),
    ("decide", {"metric": ["pc"]}, r"Decider.decide: metric = \['pc'\] is not a string"),
    ("visible_voxels", {"threads": 1.5}, r"Decider.visible_voxels: threads = 1.5 is not None or an int"),
])
def test_evaluator_options_of_the_wrong_type_are_named_briefly(world, method, keywords, message):
    """pybind11 alone would list every argument given, the views and rays in full (17 kB)."""
    evaluator = nbv.Decider()
    views = nbv.dome48()
    first = views[0] if method == "visible_voxels" else views
    with pytest.raises(nbv.InvalidArgument, match=message) as error:
        getattr(evaluator, method)(world, first, nbv.ray_set("released"), **keywords)
    assert len(str(error.value)) < 120


@pytest.mark.parametrize("method, typo", [("evaluate", "metric"), ("decide", "metrics"), ("visible_voxels", "visiblity")])
def test_unknown_keywords_are_named_with_the_known_ones(world, method, typo):
    """test_package.py checks that the known keywords listed are the method's parameters."""
    evaluator = nbv.Decider()
    views = nbv.dome48()
    first = views[0] if method == "visible_voxels" else views
    with pytest.raises(nbv.InvalidArgument, match=rf"^Decider.{method}: unknown keyword '{typo}' \(known: map, "):
        getattr(evaluator, method)(world, first, RAYS, **{typo: "x"})


def test_several_unknown_keywords_are_named_at_once(world):
    with pytest.raises(nbv.InvalidArgument, match=r"^Decider.evaluate: unknown keywords 'metric', 'thread' \(known: "):
        nbv.Decider().evaluate(world, nbv.dome48(), RAYS, metric="pc", thread=1)


def test_a_map_that_is_not_a_map_is_named(world):
    evaluator = nbv.Decider()
    with pytest.raises(nbv.InvalidArgument, match=r"Decider.evaluate: map = '/tmp/map.vdb' is not an nbv.OccupancyMap"):
        evaluator.evaluate("/tmp/map.vdb", nbv.dome48(), RAYS)
    with pytest.raises(nbv.InvalidArgument, match=r"map = array\(\[\[0\., 0\., 0\.\], \[0\., 0\., 0\.\], .*\.\.\. is not an nbv.OccupancyMap") as error:
        evaluator.visible_voxels(np.zeros((1000, 3)), nbv.dome48()[0], RAYS)
    assert len(str(error.value)) < 200
    table = evaluator.evaluate(world, nbv.dome48(), RAYS, threads=None, isa=None, seed=np.uint64(3))
    assert table.values.shape == (48, 2)


def test_meshes_and_models_may_be_paths(tmp_path):
    """A mesh file may be given as a str or an os.PathLike, to load_mesh and to reconstruct."""
    mesh = nbv.Mesh(np.array([[0, 0, 0], [1, 0, 0], [0, 1, 0], [0, 0, 1]], np.float64),
                    np.array([[0, 1, 2], [0, 1, 3], [0, 2, 3], [1, 2, 3]]))
    path = tmp_path / "tetrahedron.off"
    vertices, faces = mesh.vertices, mesh.faces
    path.write_text("OFF\n4 4 0\n" + "".join(f"{x} {y} {z}\n" for x, y, z in vertices)
                    + "".join(f"3 {a} {b} {c}\n" for a, b, c in faces))
    by_path, by_str = nbv.load_mesh(path), nbv.load_mesh(str(path))
    np.testing.assert_array_equal(by_path.vertices, by_str.vertices)
    run = nbv.reconstruct(path, iterations=1)
    assert run["model"] == str(path)


def test_too_many_candidate_views():
    with pytest.raises(nbv.InvalidArgument, match=r"fibonacciSphere: 10000000000 views; expected 1 to 10000000"):
        nbv.fibonacci_sphere(10**10)


def test_bad_views(world):
    evaluator = nbv.Decider()
    with pytest.raises(nbv.InvalidArgument, match=r"views: shape \(4, 3, 3\) is not \(N, 4, 4\)"):
        evaluator.evaluate(world, np.zeros((4, 3, 3)), RAYS)
    scaled = nbv.dome48()[:2].copy()
    scaled[1, :3, :3] *= 2.0
    with pytest.raises(nbv.InvalidArgument, match=r"views\[1\] is not a finite rigid transform"):
        evaluator.evaluate(world, scaled, RAYS)
    broken = nbv.dome48()[:1].copy()
    broken[0, 3, 0] = 1.0
    with pytest.raises(nbv.InvalidArgument, match=r"views\[0\] is not a finite rigid"):
        evaluator.evaluate(world, broken, RAYS)
    # A single (4, 4) pose is named without an index it does not have.
    with pytest.raises(nbv.InvalidArgument, match=r"^views is not a finite rigid"):
        evaluator.evaluate(world, broken[0], RAYS)
    with pytest.raises(nbv.InvalidArgument, match=r"^T_world_camera is not a finite rigid"):
        nbv.DepthCamera().render(nbv.load_mesh("bunny"), broken[0])
    with pytest.raises(nbv.InvalidArgument, match=r"views: dtype int64"):
        evaluator.evaluate(world, np.zeros((1, 4, 4), np.int64), RAYS)


def test_every_list_of_metrics_is_the_table(world):
    """The metric table is the one list: every help text, "known" list and the CSV's columns."""
    names = ", ".join(nbv.METRICS)
    assert nbv.METRICS[:2] == ("entropy", "oa") and "random" in nbv.METRICS
    assert f"a comma-separated list of: {names}" in " ".join(run_cli("evaluate", "--help").split())
    assert f"IG metric: {names}, or a weighted sum" in " ".join(run_cli("reconstruct", "--help").split())
    for call in (lambda: nbv.Decider().evaluate(world, nbv.dome48()[:1], RAYS, metrics=("bogus",)),
                 lambda: nbv.reconstruct("bunny", metric="bogus", iterations=1)):
        with pytest.raises(nbv.InvalidArgument, match=re.escape(f"unknown metric 'bogus' (known: {names})")):
            call()
    table = nbv.Decider().evaluate(world, nbv.dome48()[:2], RAYS, metrics="all")
    assert tuple(table.metrics) == nbv.METRICS
    # A comma-separated string is the list, as experiment() and the command line take it.
    listed = nbv.Decider().evaluate(world, nbv.dome48()[:2], RAYS, metrics="oa, pc")
    assert tuple(listed.metrics) == ("oa", "pc")
    assert np.array_equal(listed.values, table.values[:, [1, nbv.METRICS.index("pc")]])
    with pytest.raises(nbv.InvalidArgument, match=r"unknown metric ''"):
        nbv.Decider().evaluate(world, nbv.dome48()[:2], RAYS, metrics="oa,,pc")


def test_bad_rays_and_metrics(world):
    evaluator = nbv.Decider()
    views = nbv.dome48()
    with pytest.raises(nbv.InvalidArgument, match="no ray direction given"):
        evaluator.evaluate(world, views, np.zeros((0, 3)))
    with pytest.raises(nbv.InvalidArgument, match="ray direction 0 is not a finite unit vector"):
        evaluator.evaluate(world, views, np.ones((2, 3)))
    with pytest.raises(nbv.InvalidArgument, match="unknown metric 'bogus'"):
        evaluator.evaluate(world, views, RAYS, metrics=("oa", "bogus"))
    with pytest.raises(nbv.InvalidArgument, match="visibility 'sideways'"):
        evaluator.evaluate(world, views, RAYS, visibility="sideways")
    with pytest.raises(nbv.InvalidArgument, match="threads 0 must be at least 1"):
        evaluator.evaluate(world, views, RAYS, threads=0)
    with pytest.raises(nbv.InvalidArgument, match="ray set 'sparse'"):
        nbv.ray_set("sparse")
    with pytest.raises(nbv.InvalidArgument, match="stride must be >= 1"):
        nbv.ray_set(0)


def test_missing_and_corrupt_files(tmp_path):
    with pytest.raises(nbv.MapFileError, match="nothere.vdb: no such file"):
        nbv.load_map(str(tmp_path / "nothere.vdb"))
    corrupt = tmp_path / "corrupt.ot"
    corrupt.write_bytes(b"# Octomap OcTree file\nid OcTree\nsize 9\nres 0.01\ndata\n\x01\x02")
    with pytest.raises(nbv.MapFileError, match="corrupt.ot"):
        nbv.load_map(str(corrupt))
    with pytest.raises(nbv.MeshFileError, match="no such file, and not a standard model name"):
        nbv.load_mesh(str(tmp_path / "nothere.off"))
    bad_views = tmp_path / "views.txt"
    bad_views.write_text("2\n0 0 0 0 0 0 1\n")
    with pytest.raises(nbv.ViewFileError, match="views.txt"):
        nbv.load_views(str(bad_views))


def test_bad_options():
    with pytest.raises(nbv.InvalidArgument, match=r"^OccupancyMap: unknown keyword 'resolutoin' \(known: resolution, p_hit, "):
        nbv.OccupancyMap(resolutoin=0.02)
    with pytest.raises(nbv.InvalidArgument, match="resolution"):
        nbv.OccupancyMap(resolution=-1.0)
    with pytest.raises(nbv.InvalidArgument, match=r"resolution = 1e-05 \(must be finite and >= 0.0001 m\)"):
        nbv.OccupancyMap(resolution=1e-5)
    with pytest.raises(nbv.InvalidArgument, match=r"invalid camera: width = 1000000 \(1 to 16384 pixels\)"):
        nbv.DepthCamera(width=10**6)
    with pytest.raises(nbv.InvalidArgument, match=r"^DepthCamera: unknown keyword 'fov' \(known: width, "):
        nbv.DepthCamera(fov=90)
    with pytest.raises(nbv.InvalidArgument, match="unknown metric 'bogus'"):
        nbv.reconstruct("bunny", metric="bogus")
    with pytest.raises(nbv.InvalidArgument, match="names 'pc' twice"):
        nbv.reconstruct("bunny", metric="pc+pc")
    with pytest.raises(nbv.InvalidArgument, match=r"^reconstruct: unknown keyword 'gama' \(known: model, metric, seed, iterations, rays, viewspace, callback, gamma, "):
        nbv.reconstruct("bunny", gama=0.5)
    with pytest.raises(nbv.InvalidArgument, match=r"faces\[0\] has vertex index 7"):
        nbv.Mesh(np.zeros((3, 3)), np.array([[0, 1, 7]]))


def test_capacity():
    m = nbv.OccupancyMap()
    m.integrate(np.array([[0.3, 0.0, 0.15]], dtype=np.float32), (0.6, 0.0, 0.15))
    # The snapshot cap is not a Python option; the voxel cap of the command line is its sibling.
    assert issubclass(nbv.CapacityError, MemoryError)


def test_save_run_refuses_what_is_not_a_run_and_leaves_the_file_as_it_was(tmp_path):
    run = nbv.reconstruct("bunny", iterations=1)
    with pytest.raises(nbv.InvalidArgument, match="save_run: run is a list, not the dict reconstruct"):
        nbv.save_run([run], tmp_path / "run.json")
    with pytest.raises(nbv.InvalidArgument, match=r"save_run: run has no anytime, stop \(not a dict of reconstruct"):
        nbv.save_run({k: v for k, v in run.items() if k not in ("stop", "anytime")}, tmp_path / "run.json")
    bad = dict(run, gamma=float("inf"))
    (tmp_path / "run.json").write_text("kept")
    with pytest.raises(nbv.InvalidArgument, match=r"save_run: run\['gamma'\] = inf is not finite"):
        nbv.save_run(bad, tmp_path / "run.json")
    with pytest.raises(nbv.FileError, match=r"nothere/run.json: cannot write \(No such file or directory\)"):
        nbv.save_run(run, tmp_path / "nothere" / "run.json")
    (tmp_path / "folder.json").mkdir()
    with pytest.raises(nbv.FileError, match="folder.json: cannot write"):
        nbv.save_run(run, tmp_path / "folder.json")
    assert (tmp_path / "run.json").read_text() == "kept"
    assert sorted(p.name for p in tmp_path.iterdir()) == ["folder.json", "run.json"]  # no temporary left


def report(run_json, html, *options, cwd=None):
    return subprocess.run([nbv_cli(), "report", str(run_json), "--html", str(html), *options], capture_output=True,
                          text=True, cwd=cwd)


@pytest.mark.parametrize("kind", ["loaded mesh", "array of poses", "mesh file"])
def test_a_run_made_in_python_is_reported_from_any_folder(tmp_path, kind):
    """The run names what its report needs: a loaded mesh's file, the poses of an array."""
    (tmp_path / "made").mkdir()
    (tmp_path / "elsewhere").mkdir()
    mesh_file = tmp_path / "made" / "box.off"
    mesh_file.write_text("OFF\n8 6 0\n0 0 0\n1 0 0\n1 1 0\n0 1 0\n0 0 1\n1 0 1\n1 1 1\n0 1 1\n"
                         "4 0 3 2 1\n4 4 5 6 7\n4 0 1 5 4\n4 1 2 6 5\n4 2 3 7 6\n4 3 0 4 7\n")
    model = {"loaded mesh": nbv.load_mesh("bunny", up="y"), "array of poses": "bunny", "mesh file": mesh_file}[kind]
    views = nbv.dome48()[::2] if kind == "array of poses" else None
    run = nbv.reconstruct(model, iterations=2, viewspace=views)
    assert run["model"] == {"loaded mesh": "bunny", "array of poses": "bunny", "mesh file": str(mesh_file)}[kind]
    assert run["scene"]["up"] == ("y" if kind == "loaded mesh" else "z")
    assert ("views" in run) == (kind == "array of poses")
    nbv.save_run(run, tmp_path / "made" / "run.json")
    done = report(tmp_path / "made" / "run.json", "run.html", cwd=tmp_path / "elsewhere")
    assert done.returncode == 0, done.stderr
    page = (tmp_path / "elsewhere" / "run.html").read_text()
    assert f'"views":[' in page and page.count("[") > 100
    if kind == "array of poses":
        assert len(json.loads(page.split("const NBV_DATA = ")[1].split(";</script>")[0])["views"]) == 24
    if kind == "mesh file":  # moved with its mesh to another machine's folder: found beside the run
        (tmp_path / "moved").mkdir()
        (tmp_path / "made" / "run.json").rename(tmp_path / "moved" / "run.json")
        mesh_file.rename(tmp_path / "moved" / "box.off")
        done = report(tmp_path / "moved" / "run.json", tmp_path / "moved.html", cwd=tmp_path / "elsewhere")
        assert done.returncode == 0, done.stderr


def test_a_report_of_a_run_on_a_mesh_of_arrays_asks_for_the_file(tmp_path):
    bunny = nbv.load_mesh("bunny")
    mesh = nbv.Mesh(bunny.vertices, bunny.faces)
    assert mesh.source is None and bunny.source == "bunny"
    nbv.save_run(nbv.reconstruct(mesh, iterations=1), tmp_path / "run.json")
    done = report(tmp_path / "run.json", tmp_path / "run.html")
    assert done.returncode == 1
    message = (r"the run was made on an nbv.Mesh of arrays, which it cannot name: give the mesh file with --model PATH "
               r"\(placed as nbv places models, up 'z'\)")
    assert re.fullmatch(rf"nbv: error: {re.escape(str(tmp_path))}/run.json: {message}\n", done.stderr), done.stderr
    assert not (tmp_path / "run.html").exists()
    done = report(tmp_path / "run.json", tmp_path / "run.html", "--model", "bunny")
    assert done.returncode == 0, done.stderr


def test_load_run_names_the_file_and_what_is_wrong(tmp_path):
    path = tmp_path / "run.json"
    with pytest.raises(nbv.FileError, match=r"nothere.json: cannot read \(No such file or directory\)"):
        nbv.load_run(tmp_path / "nothere.json")
    nbv.save_run(nbv.reconstruct("bunny", iterations=2), path)
    good = json.loads(path.read_text())
    cases = [
        ("{", r"run.json: not JSON \(Expecting property name"),
        ("[1, 2]", r"run.json: not a run of nbv reconstruct --json \(a JSON list\)"),
        (json.dumps({k: v for k, v in good.items() if k != "stop"}), r"not a run of nbv reconstruct --json \(no stop\)"),
        (json.dumps(dict(good, gamma="0")), r"run.json: gamma = '0' is not a number"),
        (json.dumps(dict(good, anytime=[0.1])), r"run.json: anytime = \[0.1\] is neither null nor an object"),
        (json.dumps(dict(good, scene=dict(good["scene"], crop=[0, 1]))), r"run.json: scene.crop = \[0, 1\] is not 6 numbers"),
        (json.dumps(dict(good, iterations=[dict(good["iterations"][0], gains={"a": 1})])),
         r"run.json: iterations\[0\].gains is not a list"),
        (json.dumps(dict(good, iterations=[dict(good["iterations"][0], gains=[1, True])])),
         r"run.json: iterations\[0\].gains = True is not a number"),
    ]
    for text, message in cases:
        path.write_text(text)
        with pytest.raises(nbv.FileError, match=message):
            nbv.load_run(path)


def test_an_experiment_refuses_bad_input_before_any_run():
    started = []
    mesh = nbv.load_mesh("bunny")
    cases = [
        (dict(models=[]), r"^experiment: models holds no model$"),
        (dict(models=5), r"^experiment: models = 5 is not a model name, a mesh file, an nbv.Mesh"),
        (dict(models=["bunny", 5]), r"^experiment: models\[1\] = 5 is not a model name, a mesh file or an nbv.Mesh$"),
        (dict(models=[mesh, mesh]), r"^experiment: models\[1\] is labelled 'mesh', as an earlier model is .* give models "
                                    r"as a dict \{label: model\}$"),
        (dict(models="bunny,bunny"), r"^experiment: models 'bunny' is labelled 'bunny', as an earlier model is"),
        (dict(models={"a,b": mesh}), r"^experiment: models\['a,b'\]'s label = 'a,b' is empty or holds a comma"),
        (dict(models={5: mesh}), r"^experiment: a key of models = 5 is not a string$"),
        (dict(models="bunny", metrics="pc,bogus"), r"unknown metric 'bogus'"),
        (dict(models="bunny", metrics="pc,pc"), r"^experiment: metric 'pc' is given twice$"),
        (dict(models="bunny", metrics=[]), r"^experiment: metrics holds no metric$"),
        (dict(models="bunny", metrics=5), r"^experiment: metrics = 5 is not a sequence of strings$"),
        (dict(models="bunny", trials=0), r"^experiment: trials = 0 is not in \[1, 1048576\]$"),
        (dict(models="bunny", trials=-1), r"^experiment: trials = -1 is not a non-negative int$"),
        (dict(models="bunny", trials=[]), r"^experiment: trials holds 0 seeds, not 1 to 1048576$"),
        (dict(models="bunny", trials=[3, 1, 3]), r"^experiment: trials names a seed twice$"),
        (dict(models="bunny", trials=[1, -2]), r"^experiment: trials = \[1, -2\] is not a sequence of non-negative ints$"),
        (dict(models="bunny", threads=0), r"^threads 0 must be at least 1$"),
        (dict(models="bunny", gama=0.5), r"^experiment: unknown keyword 'gama' \(known: models, metrics, trials, iterations, rays, viewspace, callback, out, shard, gamma, "),
        (dict(models="bunny", iterations=0), r"^experiment: iterations = 0 is not a positive int$"),
        (dict(models="nothere.ply"), r"nothere.ply"),
    ]
    for kwargs, message in cases:
        with pytest.raises((nbv.InvalidArgument, nbv.FileError), match=message):
            nbv.experiment(**kwargs, callback=started.append)
    assert started == []
    with pytest.raises(nbv.InvalidArgument, match=r"experiment: the callback's answer = 'yes' is not True or False"):
        nbv.experiment("bunny", metrics="pc", trials=1, iterations=1, callback=lambda run: "yes")


def test_a_run_of_an_earlier_version_lacks_the_fields_added_since_and_still_tabulates():
    """Every field of the record's table is in an iteration's dict; a run whose iterations lack
    those added after the first version (rays, ray_share: a file of an earlier nbv read by
    load_run) gives the rows of a run without them, the fields at 0."""
    run = nbv.reconstruct("bunny", iterations=2)
    assert [name for name, _, _ in nbv._ITERATION_FIELDS] == [k for k in run["iterations"][0] if k != "gains"]
    assert run["iterations"][0]["ray_share"] == 1.0 and run["iterations"][1]["ray_share"] == 0.0
    old = dict(run, iterations=[{k: v for k, v in it.items() if k not in ("rays", "ray_share")} for it in run["iterations"]])
    rows = nbv._results_csv([old]).splitlines()
    assert rows[0].endswith(",rays,ray_share")
    assert rows[1].endswith(",0,0") and rows[1].rsplit(",", 2)[0] == nbv._results_csv([run]).splitlines()[1].rsplit(",", 2)[0]


def test_table1_and_save_experiment_name_the_run_at_fault_and_write_nothing(tmp_path):
    run = nbv.reconstruct("bunny", iterations=2)
    first = run["iterations"][0]
    cases = [
        (run, r"^table1: runs = \{.* is not a sequence of runs"),
        ("runs", r"^table1: runs = 'runs' is not a sequence of runs"),
        ([run, 5], r"^table1: runs\[1\] is a int, not the dict of a run$"),
        ([{k: v for k, v in run.items() if k != "seed"}], r"^table1: runs\[0\] has no 'seed' \(not a run of reconstruct"),
        ([run, dict(run)], r"^table1: runs\[1\] repeats model 'bunny', metric 'pc' and seed 0 of an earlier run$"),
        ([dict(run, max_entropy_bits=0.0)], r"^table1: runs\[0\]\['max_entropy_bits'\] = 0.000000 is not a positive number$"),
        ([dict(run, model="a\nb")], r"^table1: runs\[0\]\['model'\] = 'a\nb' is empty or holds a comma"),
        ([dict(run, iterations=run["iterations"][::-1])], r"^table1: runs\[0\]\['iterations'\]\[0\]\['iteration'\] = 2, not 1$"),
        ([dict(run, iterations=[dict(first, coverage="high")])],
         r"^table1: runs\[0\]\['iterations'\]\[0\]\['coverage'\] = 'high' is not a number$"),
        ([dict(run, iterations=[{k: v for k, v in first.items() if k != "gains"}])],
         r"^table1: runs\[0\]\['iterations'\]\[0\] has no 'gains'"),
        ([dict(run, iterations=[{k: v for k, v in first.items() if k != "gap"}])],
         r"^table1: runs\[0\]\['iterations'\]\[0\] has no 'gap'"),
    ]
    for runs, message in cases:
        with pytest.raises(nbv.InvalidArgument, match=message):
            nbv.table1(runs)
        with pytest.raises(nbv.InvalidArgument, match=message.replace("table1", "save_experiment")):
            nbv.save_experiment(runs, tmp_path / "out")
    assert not (tmp_path / "out").exists()
    (tmp_path / "file").write_text("kept")
    with pytest.raises(nbv.FileError, match=r"file: cannot make the folder"):
        nbv.save_experiment([run], tmp_path / "file")
    (tmp_path / "out").mkdir()
    (tmp_path / "out" / "table.md").mkdir()  # results.csv is written, table.md cannot be
    with pytest.raises(nbv.FileError, match=r"out/table.md: cannot write"):
        nbv.save_experiment([run], tmp_path / "out")
    assert sorted(p.name for p in (tmp_path / "out").iterdir()) == ["results.csv", "table.md"]  # no temporary left
    assert (tmp_path / "file").read_text() == "kept"
