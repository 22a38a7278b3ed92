"""The package as a whole: no copies where none is promised, the GIL released, documented."""
import ast
import inspect
import threading
import tracemalloc
import warnings

import numpy as np
import pytest

import nbv


def traced_peak(call):
    """Bytes numpy allocated (it reports its buffers to tracemalloc) while `call` ran."""
    tracemalloc.start()
    try:
        call()
        return tracemalloc.get_traced_memory()[1]
    finally:
        tracemalloc.stop()


def test_points_are_read_in_place():
    points = np.random.default_rng(0).uniform(-0.3, 0.3, size=(400_000, 3)).astype(np.float32)
    points[:, 2] += 0.3
    m = nbv.OccupancyMap()
    in_place = traced_peak(lambda: m.integrate(points, (0.6, 0.0, 0.15)))
    converted = traced_peak(lambda: nbv.OccupancyMap().integrate(points.astype(np.float64), (0.6, 0.0, 0.15)))
    assert in_place < points.nbytes / 10, in_place        # C-contiguous float32: no copy
    assert converted >= points.nbytes, converted          # float64: one float32 copy (and the astype)


def test_table_values_are_the_tables_memory():
    m = nbv.OccupancyMap()
    m.integrate(np.array([[0.3, 0.0, 0.15]], dtype=np.float32), (0.6, 0.0, 0.15))
    table = nbv.Decider().evaluate(m, nbv.dome48(), nbv.ray_set(16), metrics=("oa", "pc"))
    values = table.values
    assert values.base is table and not values.flags["OWNDATA"] and not values.flags["WRITEABLE"]
    assert values.ctypes.data == table.values.ctypes.data  # the same memory on every access
    assert np.shares_memory(table["pc"], values)
    with pytest.raises(KeyError):
        table["vg"]


def test_table_reads_as_a_data_frame_of_metric_columns():
    """len: views; iteration and `in`: metric names; numpy.asarray: the values."""
    m = nbv.OccupancyMap()
    m.integrate(np.array([[0.3, 0.0, 0.15]], dtype=np.float32), (0.6, 0.0, 0.15))
    table = nbv.Decider().evaluate(m, nbv.dome48()[:5], nbv.ray_set(16), metrics=("oa", "pc"))
    assert len(table) == 5 and list(table) == ["oa", "pc"]
    assert "pc" in table and "vg" not in table and "nonsense" not in table and 0 not in table
    assert np.shares_memory(np.asarray(table), table.values)
    np.testing.assert_array_equal(np.column_stack([table[name] for name in table]), table.values)
    with pytest.raises(KeyError, match=r"columns are metric names \(\['oa', 'pc'\]\), not 0; a view's row is"):
        table[0]


def test_two_threads_give_the_tables_of_one():
    mesh = nbv.load_mesh("bunny")
    views = nbv.dome48()
    maps = []
    for first in (0, 20):
        m = nbv.OccupancyMap()
        for index in (first, first + 9):
            _, points = nbv.DepthCamera().render(mesh, views[index])
            m.integrate(points, views[index][:3, 3])
        maps.append(m)
    rays = nbv.ray_set(6)
    alone = [nbv.Decider().evaluate(m, views, rays, metrics="all").values.copy() for m in maps]
    together = [None, None]

    def work(i):
        together[i] = nbv.Decider().evaluate(maps[i], views, rays, metrics="all").values.copy()

    threads = [threading.Thread(target=work, args=(i,)) for i in range(2)]
    for t in threads:
        t.start()
    for t in threads:
        t.join()
    for a, b in zip(alone, together):
        np.testing.assert_array_equal(a, b)


def test_the_public_names_are_those_of_all():
    """Tab completion on nbv offers the package's names, not the modules it imports."""
    assert {n for n in dir(nbv) if not n.startswith("_")} == set(nbv.__all__)


def test_every_public_name_is_documented():
    for name in nbv.__all__:
        item = getattr(nbv, name)
        assert item.__doc__ and len(item.__doc__.strip()) > 20, name
        if inspect.isclass(item) and not issubclass(item, BaseException):
            for member, value in vars(item).items():
                if not member.startswith("_") and callable(value):
                    assert value.__doc__ and len(value.__doc__.strip()) > 20, f"{name}.{member}"


def parameters_of(text, opening):
    """The parameters (name, default or None) of the signature in `text` whose "(" is at `opening`."""
    depth, parts, part = 0, [], ""
    for c in text[opening + 1:]:
        depth += c in "([{"
        depth -= c in ")]}"
        if depth < 0:
            break
        if c == "," and depth == 0:
            parts, part = parts + [part], ""
        else:
            part += c
    parameters = []
    for p in parts + [part]:
        head, _, default = p.partition("=")
        name = head.split(":")[0].strip()
        parameters.append(("**kwargs" if name.startswith("**") else name, default.strip() or None))
    return [p for p in parameters if p[0] not in ("", "self")]


def documented_parameters(name, doc):
    """The parameters of the signature a docstring opens with: `name(...)`."""
    text = doc.lstrip()
    assert text.startswith(name + "("), f"{name}: the docstring opens with {text[:40]!r}"
    return parameters_of(text, len(name))


def recorded_parameters(function):
    """The parameters of `function` (of a class: of its constructor): a Python function's own
    (those of the functions nbv checks the arguments of), or those pybind11 recorded, as its
    TypeError for too many arguments lists them."""
    if inspect.isclass(function) and inspect.isfunction(function.__init__):
        function = function.__init__
    if inspect.isfunction(function):
        return [("**kwargs" if p.kind == p.VAR_KEYWORD else p.name, None if p.default is p.empty else repr(p.default))
                for p in inspect.signature(function).parameters.values() if p.name != "self"]
    with pytest.raises(TypeError, match="incompatible") as error:
        function(*[None] * 40)
    supported = error.value.args[0].splitlines()[1]
    assert "2. " not in error.value.args[0], "one overload"
    return parameters_of(supported, supported.index("("))


def same_default(documented, recorded):
    if documented is None or recorded is None:
        return documented == recorded
    return ast.literal_eval(documented) == ast.literal_eval(recorded)


def bound_callables():
    """(the name a docstring opens with, the callable) for each function, constructor and method."""
    for name in nbv.__all__:
        item = getattr(nbv, name)
        if not inspect.isclass(item):
            if callable(item):
                yield name, item
        elif not issubclass(item, BaseException):
            if item is not nbv.IgTable:  # made by evaluate(), not by users
                yield name, item
            for member, value in vars(item).items():
                if not member.startswith("_") and callable(value):
                    yield member, value


@pytest.mark.parametrize("name, function", [pytest.param(n, f, id=n) for n, f in bound_callables()])
def test_each_docstring_opens_with_the_signature_it_takes(name, function):
    """help() shows the docstring's signature alone: its names, order and defaults are the function's."""
    doc = (function.__init__ if inspect.isclass(function) else function).__doc__
    documented = documented_parameters(name, doc)
    recorded = recorded_parameters(function)
    assert [n for n, _ in documented] == [n for n, _ in recorded]
    for (n, mine), (_, theirs) in zip(documented, recorded):
        assert same_default(mine, theirs), f"{name}: {n}={mine} in the docstring, {theirs} in the signature"


def test_a_keyword_not_taken_is_named_with_the_ones_taken():
    """Each function of the compiled module with parameters lists them, then its keyword options,
    when given another (those written in Python, such as save_run, raise Python's TypeError)."""
    for name, function, call in owned_callables():
        parameters = [n for n, _ in recorded_parameters(function) if n != "**kwargs"]
        checker = function.__init__ if inspect.isclass(function) else function
        if not parameters or not checker.__code__.co_filename.endswith("_arguments.py"):
            continue
        with pytest.raises(nbv.InvalidArgument, match="unknown keyword 'no_such_keyword'") as error:
            call(no_such_keyword=1)
        known = str(error.value).split("(known: ")[1].rstrip(")").split(", ")
        assert known[:len(parameters)] == parameters, f"{name}: the refusal lists other keywords than it takes"


def an_instance_of(cls):
    """An object of each class whose methods the argument checks call."""
    return {nbv.OccupancyMap: nbv.OccupancyMap, nbv.DepthCamera: nbv.DepthCamera, nbv.Decider: nbv.Decider,
            nbv.Mesh: lambda: nbv.load_mesh("bunny"),
            nbv.SurfaceCoverage: lambda: nbv.SurfaceCoverage(np.zeros((5, 3)))}[cls]()


def owned_callables():
    """(name, the callable as a user calls it) of each function, constructor and method."""
    for name, function in bound_callables():
        owner = next((getattr(nbv, c) for c in nbv.__all__ if inspect.isclass(getattr(nbv, c))
                      and vars(getattr(nbv, c)).get(name) is function), None)
        yield name, function, (getattr(an_instance_of(owner), name) if owner is not None else function)


@pytest.mark.parametrize("name, function, call", [pytest.param(n, f, c, id=n) for n, f, c in owned_callables()])
def test_no_argument_value_meets_pybind11s_type_error(name, function, call):
    """Every parameter takes any Python value and names it when it cannot use it: pybind11's
    "incompatible function arguments" (the arguments listed, arrays in full) never shows."""
    parameters = [(n, d) for n, d in recorded_parameters(function) if n != "**kwargs"]
    required = sum(1 for _, d in parameters if d is None)
    for count in {required, len(parameters)} - {0}:
        try:
            call(*[object()] * count)
        except TypeError as error:
            assert "incompatible" not in str(error), f"{name}({count} arguments): {error}"
        except Exception:  # noqa: BLE001 (nbv's own errors, which name the argument)
            pass


def test_views_and_rays():
    dome = nbv.dome48()
    assert dome.shape == (48, 4, 4) and dome.dtype == np.float64
    np.testing.assert_allclose(dome[0][:3, 3], (0.6, 0.0, 0.15))
    sphere = nbv.fibonacci_sphere(200, 0.6, (0, 0, 0.2), min_z=0.0)
    assert 100 < len(sphere) < 200 and (sphere[:, 2, 3] >= 0.0).all()
    assert nbv.ray_set("released").shape == (950, 3)
    shipped = nbv.ray_set("released-shipped")  # the shipped launch file's window, off the axis
    assert shipped.shape == (950, 3) and shipped[:, 0].mean() < -0.2 and shipped[:, 1].mean() > 0.2
    assert nbv.ray_set("full").shape == (360960, 3)
    np.testing.assert_allclose(np.linalg.norm(nbv.ray_set(10), axis=1), 1.0)


def test_views_round_trip_through_a_file(tmp_path):
    path = str(tmp_path / "views.txt")
    nbv.save_views(path, nbv.dome48())
    np.testing.assert_allclose(nbv.load_views(path), nbv.dome48(), atol=1e-12)


def test_meshes_from_arrays_and_files(tmp_path):
    bunny = nbv.load_mesh("bunny")
    lo, hi = bunny.bounds
    assert abs((hi - lo).max() - 0.5) < 1e-6 and abs(lo[2]) < 1e-6
    back = np.linalg.inv(bunny.transform)  # maps the placed mesh back to the file's frame
    assert np.isfinite(back).all()
    box = nbv.Mesh(np.array([[0, 0, 0], [1, 0, 0], [0, 1, 0]], np.float64) * 0.2 + (0, 0, 0.1),
                   np.array([[0, 1, 2]]))
    depth, points = nbv.DepthCamera().render(box, nbv.dome48()[0])
    assert depth.shape == (480, 752)


def test_a_model_name_or_file_goes_wherever_a_mesh_does(tmp_path):
    """render() and sample_surface() take what reconstruct() takes: a name, a path, a Mesh."""
    view = nbv.dome48()[0]
    depth, points = nbv.DepthCamera().render("bunny", view)
    np.testing.assert_array_equal(depth, nbv.DepthCamera().render(nbv.load_mesh("bunny"), view)[0])
    np.testing.assert_array_equal(nbv.sample_surface("bunny", 1000, seed=3),
                                  nbv.sample_surface(nbv.load_mesh("bunny"), 1000, seed=3))
    off = tmp_path / "tri.off"
    off.write_text("OFF\n3 1 0\n0 0 0\n1 0 0\n0 1 0\n3 0 1 2\n")
    assert nbv.sample_surface(off, 10).shape == (10, 3)        # an os.PathLike
    assert nbv.sample_surface(str(off), 10).shape == (10, 3)   # a str
    assert nbv.load_mesh(off).source == str(off)  # the absolute path a saved run names
    assert nbv.load_mesh("bunny").source == "bunny"


def test_the_old_name_of_the_decider_still_works_with_a_warning():
    with pytest.warns(DeprecationWarning, match=r"nbv.IgEvaluator is now nbv.Decider"):
        assert nbv.IgEvaluator is nbv.Decider
    assert "IgEvaluator" not in nbv.__all__
    with pytest.raises(AttributeError, match="no attribute 'IgEvaluatr'"):
        nbv.IgEvaluatr


def test_every_map_configuration_field_is_a_keyword_a_config_key_and_a_line_of_the_docstring(tmp_path):
    defaults = nbv.OccupancyMap().config
    assert list(defaults) == ["resolution", "p_hit", "p_miss", "clamp_min", "clamp_max", "max_range",
                              "proximity_range", "occupied_threshold", "free_threshold", "min_range"]
    # Every field off its default by a value its check takes: given, kept, saved and read back.
    given = {"resolution": 0.02, "p_hit": 0.72, "p_miss": 0.41, "clamp_min": 0.11, "clamp_max": 0.96,
             "max_range": 2.5, "proximity_range": 0.25, "occupied_threshold": 0.79, "free_threshold": 0.21,
             "min_range": 0.05}
    assert set(given) == set(defaults) and all(given[k] != defaults[k] for k in given)
    m = nbv.OccupancyMap(**given)
    assert m.config == given
    m.save(tmp_path / "m.vdb")
    assert nbv.load_map(tmp_path / "m.vdb").config == given
    # An OctoMap file holds the resolution alone: the rest comes from the keywords.
    m.save(tmp_path / "m.bt")
    rest = {k: v for k, v in given.items() if k != "resolution"}
    assert nbv.load_map(tmp_path / "m.bt", **rest).config == given
    for name in defaults:
        assert f"\n  {name}" in nbv.OccupancyMap.__init__.__doc__, name
        with pytest.raises(nbv.InvalidArgument, match=rf"invalid map configuration: {name} = nan \("):
            nbv.OccupancyMap(**{name: float("nan")})


def test_maps_round_trip_and_answer_queries(tmp_path):
    m = nbv.OccupancyMap(resolution=0.02, p_hit=0.75)
    m.integrate(np.array([[0.305, 0.005, 0.005]], np.float32), (0.005, 0.005, 0.005))
    assert m.config["p_hit"] == 0.75 and m.resolution == 0.02
    assert repr(m) == f"<nbv.OccupancyMap resolution=0.02 m, {m.counts()['measured']} measured voxels>"
    p = m.probability(np.array([[0.305, 0.005, 0.005], [5.0, 5.0, 5.0]]))
    assert p[0] == pytest.approx(0.75) and p[1] == 0.5
    path = str(tmp_path / "m.vdb")
    m.save(path)
    again = nbv.load_map(path)
    assert again.counts() == m.counts()
    np.testing.assert_array_equal(again.log_odds(np.array([[0.305, 0.005, 0.005]])), m.log_odds(np.array([[0.305, 0.005, 0.005]])))
    lo, hi = m.bounds()
    assert (hi > lo).all()
    assert nbv.OccupancyMap().bounds() is None


def test_the_ground_plane_is_seen_and_labelled():
    mesh = nbv.load_mesh("bunny", up="y")
    camera = nbv.DepthCamera()
    view = nbv.dome48()[0]
    _, alone = camera.render(mesh, view)
    depth, points, on_object = camera.render(mesh, view, ground_plane=True, labels=True)
    assert points.shape[0] == on_object.shape[0] > alone.shape[0]
    assert on_object.dtype == bool and 0 < on_object.sum() <= alone.shape[0]
    assert np.abs(points[~on_object][:, 2]).max() < 1e-6  # the plane is z = 0


def test_a_depth_frame_integrates_as_its_points():
    mesh = nbv.load_mesh("bunny")
    camera = nbv.DepthCamera()
    view = nbv.dome48()[16]
    depth, _ = camera.render(mesh, view)
    raw = np.round(depth * 5000.0).astype(np.uint16)
    a, b = nbv.OccupancyMap(), nbv.OccupancyMap()
    a.integrate_depth(raw, view, camera)
    b.integrate_depth(raw.astype(np.float32) / np.float32(5000.0), T_world_camera=view)  # float metres
    assert a.counts()["octomap_occupied"] > 1000
    assert abs(a.counts()["measured"] - b.counts()["measured"]) < 0.01 * a.counts()["measured"]
    c = nbv.OccupancyMap()
    c.integrate_depth(raw, view, camera, no_return="clear")
    assert c.counts()["measured"] > 3 * a.counts()["measured"]
    with pytest.raises(nbv.InvalidArgument, match="depth image of 10 x 4 pixels"):
        a.integrate_depth(np.zeros((4, 10), np.uint16), view, camera)
    with pytest.raises(nbv.InvalidArgument, match="dtype int32"):
        a.integrate_depth(np.zeros((480, 752), np.int32), view, camera)


def test_a_dataset_camera_flips_rows_by_a_negative_focal_length():
    # ICL-NUIM's intrinsics carry fy < 0: the frame stored upside down under fy' = -fy and
    # cy' = H - 1 - cy gives every pixel its ray: the same map.
    mesh = nbv.load_mesh("bunny")
    camera = nbv.DepthCamera()
    flipped = nbv.DepthCamera(fy=-camera.fy, cy=camera.height - 1 - camera.cy)
    view = nbv.dome48()[16]
    depth, _ = camera.render(mesh, view)
    raw = np.round(depth * 5000.0).astype(np.uint16)
    a, b = nbv.OccupancyMap(), nbv.OccupancyMap()
    a.integrate_depth(raw, view, camera)
    b.integrate_depth(raw[::-1].copy(), view, flipped)
    assert a.counts() == b.counts() and a.counts()["measured"] > 1000
    with pytest.raises(nbv.InvalidArgument, match="fy = 0"):
        nbv.DepthCamera(fy=0.0)


def test_dataset_frames_load_in_order_and_integrate_as_the_command_line(tmp_path):
    # A TUM folder as `nbv render --tum-out` writes it, and the same frames as a numbered folder
    # with a pose file without timestamps: the same poses, and the map `nbv integrate --tum` makes.
    from conftest import run_cli
    tum, numbered = tmp_path / "tum", tmp_path / "numbered"
    run_cli("viewspace", "--kind", "fibonacci", "--count", "3", "--radius", "0.6", "--target", "0", "0", "0.15",
            "--out", tmp_path / "three.txt")
    run_cli("render", "--model", "bunny", "--views", tmp_path / "three.txt", "--tum-out", tum)
    numbered.mkdir()
    lines = [line.split()[1:] for line in (tum / "groundtruth.txt").read_text().splitlines() if not line.startswith("#")]
    (tmp_path / "poses.txt").write_text("".join(" ".join(fields) + "\n" for fields in lines))
    for i, png in enumerate(sorted((tum / "depth").iterdir())):
        (numbered / f"frame_{i}.png").write_bytes(png.read_bytes())
    by_time, by_number = nbv.load_frames(tum), nbv.load_frames(numbered, tmp_path / "poses.txt")
    assert len(by_time) == len(by_number) == 3
    world = nbv.OccupancyMap()
    for (path, pose), (_, same_pose) in zip(by_time, by_number):
        assert np.array_equal(pose, same_pose) and pose.shape == (4, 4)
        depth = nbv.load_depth_png(path)
        assert depth.dtype == np.uint16 and depth.shape == (480, 752)
        world.integrate_depth(depth, pose)
    run_cli("integrate", "--map", tmp_path / "tum.vdb", "--tum", tum)
    assert world.counts() == nbv.load_map(str(tmp_path / "tum.vdb")).counts()
    with pytest.raises(nbv.FileError, match="poses.txt"):
        nbv.load_frames(numbered, tmp_path / "missing" / "poses.txt")


def test_discretize_casts_one_ray_per_end_voxel():
    mesh = nbv.load_mesh("bunny")
    view = nbv.dome48()[16]
    _, points = nbv.DepthCamera().render(mesh, view)
    world = nbv.OccupancyMap()
    stats = world.integrate(points, view[:3, 3], discretize=True)
    assert stats["points"] == len(points) and 0 < stats["hits"] == stats["voxels_hit"] < len(points) / 5
    with pytest.raises(nbv.InvalidArgument, match="discretize"):
        world.integrate(points, view[:3, 3], discretize="yes")


def test_an_octomap_file_takes_its_configuration_and_a_far_scan_warns(tmp_path):
    # An OctoMap file holds no range: load_map gives the map the one its scans need, and a scan
    # mostly beyond a map's range says so.
    m = nbv.OccupancyMap(resolution=0.05, max_range=6.0)
    m.integrate(np.array([[5.0, 0.1, 0.0], [4.0, -0.2, 0.3]]), (0.0, 0.0, 0.0))
    m.save(str(tmp_path / "far.bt"))
    default = nbv.load_map(str(tmp_path / "far.bt"))
    assert default.config["max_range"] == 1.5
    ranged = nbv.load_map(str(tmp_path / "far.bt"), max_range=6.0, p_hit=0.8)
    assert ranged.config["max_range"] == 6.0 and ranged.config["p_hit"] == 0.8 and ranged.resolution == 0.05
    assert ranged.counts() == default.counts()
    scan = np.array([[5.5, 0.0, 0.0], [5.0, 0.5, 0.1], [0.5, 0.0, 0.0]])
    with pytest.warns(UserWarning, match="2 of the scan's 3 points lie beyond the map's max_range of 1.5 m"):
        default.integrate(scan, (0.0, 0.0, 0.0))
    with warnings.catch_warnings():
        warnings.simplefilter("error")
        ranged.integrate(scan, (0.0, 0.0, 0.0))
    with pytest.raises(nbv.MapFileError, match="more than the cap"):
        nbv.load_map(str(tmp_path / "far.bt"), max_map_mb=0)
    with pytest.raises(nbv.InvalidArgument, match="unknown keyword 'range'"):
        nbv.load_map(str(tmp_path / "far.bt"), range=6.0)


def test_a_map_keeps_its_ranges_and_drops_points_nearer_than_its_minimum():
    world = nbv.OccupancyMap(max_range=3.0, min_range=0.5)
    assert world.config["max_range"] == 3.0 and world.config["min_range"] == 0.5
    points = np.array([[0.2, 0.0, 0.0], [1.0, 0.0, 0.0], [4.0, 0.0, 0.0]])
    stats = world.integrate(points, (0.0, 0.0, 0.0))
    assert (stats["too_near"], stats["hits"], stats["beyond_range"]) == (1, 1, 1)
    with pytest.raises(nbv.InvalidArgument, match="min_range"):
        nbv.OccupancyMap(max_range=1.0, min_range=1.0)
