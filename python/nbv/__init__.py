"""nbv: next-best-view planning with fast volumetric information gain.

Build a probabilistic voxel map of an object from depth scans, score candidate camera poses by
the information gain of the rays they would cast, and pick the next best view, as in Delmerico
et al., "A comparison of volumetric information gain metrics for active 3D object
reconstruction" (Autonomous Robots, 2018). The numbers are those of the `nbv` command line:
docs/SEMANTICS.md of the repository defines each of them.

Conventions: arrays are numpy; points are (N, 3) float32 or float64 in metres, world frame; a
single point (an origin, a centre, a target) is any (3,) sequence of numbers; poses are
T_world_camera (camera -> world) as (4, 4) or (N, 4, 4) float64, optical frame z forward, x
along image columns, y along rows; ray directions are (R, 3) unit vectors in the camera frame.
Errors raise nbv.InvalidArgument (a ValueError), nbv.FileError (an OSError) and its
subclasses, or nbv.CapacityError (a MemoryError), with the C++ message.

    import nbv
    mesh = nbv.load_mesh("bunny")
    camera = nbv.DepthCamera()
    views = nbv.dome48()
    world = nbv.OccupancyMap(resolution=0.01)
    depth, points = camera.render(mesh, views[0])
    world.integrate(points, views[0][:3, 3])
    table = nbv.Decider().evaluate(world, views, nbv.ray_set("released"), metrics=("pc",))
    best = int(table["pc"].argmax())
"""

import functools as _functools
import json as _json
import math as _math
import os as _os
import secrets as _secrets

import numpy as _np

from ._nbv import _ITERATION_FIELDS  # the iteration record's table: (name, kind, help) per field
from ._nbv import _DECIDE_OPTIONS, _RECONSTRUCTION_OPTIONS  # option tables: name -> (optional, default)
from ._nbv import (  # noqa: F401  (the names users call)
    CapacityError,
    CloudFileError,
    DepthCamera,
    FileError,
    Decider,
    IgTable,
    InvalidArgument,
    METRICS,
    MapFileError,
    Mesh,
    MeshFileError,
    OccupancyMap,
    SceneError,
    ViewFileError,
    __version__,
    dome48,
    isa,
    model_search_path,
    SurfaceCoverage,
)
# The functions that take arguments, each checked by kind before the compiled one runs; the
# classes' methods are checked in place.
from ._signatures import (  # noqa: F401
    _results_csv,
    experiment,
    fetch_models,
    fibonacci_sphere,
    load_depth_png,
    load_frames,
    load_map,
    load_mesh,
    load_views,
    map_entropy_bits,
    ray_set,
    reconstruct,
    sample_surface,
    save_views,
    start_view,
    surface_coverage,
    table1,
)

__all__ = [
    "CapacityError", "CloudFileError", "DepthCamera", "FileError", "Decider", "IgTable",
    "InvalidArgument", "METRICS", "MapFileError", "Mesh", "MeshFileError", "OccupancyMap", "SceneError",
    "ViewFileError", "dome48", "experiment", "fetch_models", "fibonacci_sphere", "isa", "load_depth_png", "load_frames", "load_map",
    "load_mesh",
    "load_run", "load_views", "map_entropy_bits", "model_search_path", "ray_set", "reconstruct", "sample_surface",
    "save_experiment", "save_run", "save_views", "start_view", "SurfaceCoverage", "surface_coverage", "table1",
]

# The reconstruction's options (gamma, g_thresh, ...: the compiled module's table), each a field of a run.
_RUN_OPTIONS = tuple(_RECONSTRUCTION_OPTIONS)
# The fields of a run, in the order `nbv reconstruct --json` writes them.
_RUN_FIELDS = ("model", "metric", "seed", "viewspace", "weighting", "rays", *_RUN_OPTIONS, "scene", "anytime", "stop",
               "iterations", "max_entropy_bits", "auc_coverage", "auc_entropy")


# The fields a run holds as floats, which a JSON file may write as integers ("gamma": 0); an
# optional option's None stays None.
_RUN_FLOATS = (*_RUN_OPTIONS, "max_entropy_bits", "auc_coverage", "auc_entropy")
# An iteration's fields as floats: every field of the record's table but the counts.
_ITERATION_FLOATS = tuple(name for name, kind, _ in _ITERATION_FIELDS if kind != "Count")


def _plain(value, where):
    """`value` as JSON takes it: arrays and numpy scalars as Python ones, NaN as None."""
    if isinstance(value, _np.ndarray):
        return [_plain(v, where) for v in value.tolist()]
    if isinstance(value, _np.generic):
        value = value.item()
    if isinstance(value, dict):
        return {str(k): _plain(v, f"{where}[{k!r}]") for k, v in value.items()}
    if isinstance(value, (list, tuple)):
        return [_plain(v, f"{where}[{i}]") for i, v in enumerate(value)]
    if isinstance(value, float):
        if _math.isnan(value):
            return None
        if _math.isinf(value):
            raise InvalidArgument(f"save_run: {where} = {value} is not finite")
    return value


def save_run(run, path):
    """save_run(run, path)

    Writes a run of reconstruct() as `nbv reconstruct --json` writes it: its fields in that
    order, arrays as lists, NaN (a visited view's gain) as null. `nbv report PATH --html PAGE`
    then draws it from any folder, re-rendering the scans: the run names its model (a standard
    name, or the absolute path of the mesh file, also of an nbv.Mesh that load_mesh() read) and
    its viewspace ("dome48", a view file's absolute path, or the poses themselves under "views"
    when they were an array); a run on an nbv.Mesh of arrays names "mesh", and the report then
    asks for the file with --model. The file is written beside `path` and renamed into
    place, so a failure leaves `path` as it was; load_run() reads it back. Raises
    nbv.InvalidArgument for anything but a dict with reconstruct()'s fields, nbv.FileError when
    `path` cannot be written.
    """
    if not isinstance(run, dict):
        raise InvalidArgument(f"save_run: run is a {type(run).__name__}, not the dict reconstruct() returns")
    missing = [f for f in _RUN_FIELDS if f not in run]
    if missing:
        raise InvalidArgument(f"save_run: run has no {', '.join(missing)} (not a dict of reconstruct())")
    ordered = {f: run[f] for f in _RUN_FIELDS}
    ordered.update((k, v) for k, v in run.items() if k not in ordered)
    text = _json.dumps(_plain(ordered, "run"), indent=2, allow_nan=False) + "\n"
    _write_atomically(_os.fspath(path), text)


def save_experiment(runs, folder):
    """save_experiment(runs, folder)

    Writes `runs` (the dicts of experiment(), reconstruct() or load_run(), each (model, metric,
    seed) once) into `folder` as `nbv experiment` does: results.csv (a line per run and
    iteration) and table.md (table1()). The folder is made if it does not exist; each file is
    written beside its place and renamed into it, so a failure leaves the file as it was.
    The folder holds no sweep and no run files: for one that `nbv experiment --merge FOLDER
    --out OUT` draws (plots, front page) and merges with other shards, run experiment() with
    out=FOLDER, which writes them as each run ends. Raises nbv.InvalidArgument for runs that are not such dicts,
    naming the run and field, nbv.FileError when the folder cannot be made or written.
    """
    csv_text, table = _results_csv(runs), table1(runs)
    folder = _os.fspath(folder)
    try:
        _os.makedirs(folder, exist_ok=True)
    except OSError as error:
        raise FileError(f"{folder}: cannot make the folder ({error.strerror or error})") from error
    _write_atomically(_os.path.join(folder, "results.csv"), csv_text)
    _write_atomically(_os.path.join(folder, "table.md"), table)


def _write_atomically(path, text):
    """Writes `text` to a new file beside `path` and renames it into place; FileError on failure."""
    temporary = f"{path}.{_os.getpid()}.{_secrets.token_hex(4)}.tmp"  # created with the umask's mode, as `path` would be
    try:
        with open(temporary, "x", encoding="utf-8") as out:
            out.write(text)
        _os.replace(temporary, path)
    except OSError as error:
        if _os.path.exists(temporary):
            _os.remove(temporary)
        raise FileError(f"{path}: cannot write ({error.strerror or error})") from error


def _run_number(path, value, where):
    """A JSON number of a run file (null: NaN) as the float reconstruct() gives."""
    if value is None:
        return _math.nan
    if isinstance(value, bool) or not isinstance(value, (int, float)):
        raise FileError(f"{path}: {where} = {value!r} is not a number")
    return float(value)


def load_run(path):
    """load_run(path) -> dict

    Reads a run that `nbv reconstruct --json` or save_run() wrote, as reconstruct() returns it:
    each iteration's gains a (V,) float64 array, NaN where the file has null. Raises
    nbv.FileError naming the file when it cannot be read, is not JSON or is not such a run.
    """
    path = _os.fspath(path)
    try:
        with open(path, encoding="utf-8") as f:
            run = _json.load(f)
    except OSError as error:
        raise FileError(f"{path}: cannot read ({error.strerror or error})") from error
    except (ValueError, UnicodeDecodeError) as error:
        raise FileError(f"{path}: not JSON ({error})") from error
    if not isinstance(run, dict):
        raise FileError(f"{path}: not a run of nbv reconstruct --json (a JSON {type(run).__name__})")
    # A file written before an option existed (only gamma was written then) reads its default.
    if "gamma" in run:
        for name, (_, default) in _RECONSTRUCTION_OPTIONS.items():
            run.setdefault(name, default)
    missing = [f for f in _RUN_FIELDS if f not in run]
    if missing:
        raise FileError(f"{path}: not a run of nbv reconstruct --json (no {', '.join(missing)})")
    number = _functools.partial(_run_number, path)
    for key in _RUN_FLOATS:
        if run[key] is not None or not _RECONSTRUCTION_OPTIONS.get(key, (False,))[0]:
            run[key] = number(run[key], key)
    anytime, scene = run["anytime"], run["scene"]
    if anytime is not None and not isinstance(anytime, dict):
        raise FileError(f"{path}: anytime = {anytime!r} is neither null nor an object")
    for key in _DECIDE_OPTIONS if anytime else ():
        if anytime.get(key) is not None:
            anytime[key] = number(anytime[key], f"anytime.{key}")
    if not isinstance(scene, dict):
        raise FileError(f"{path}: scene = {scene!r} is not an object")
    if scene.get("crop") is not None:
        if not isinstance(scene["crop"], list) or len(scene["crop"]) != 6:
            raise FileError(f"{path}: scene.crop = {scene['crop']!r} is not 6 numbers")
        scene["crop"] = tuple(number(v, "scene.crop") for v in scene["crop"])
    iterations = run["iterations"]
    if not isinstance(iterations, list) or not all(isinstance(it, dict) and "gains" in it for it in iterations):
        raise FileError(f"{path}: iterations is not a list of records with gains")
    for i, it in enumerate(iterations):
        for key in _ITERATION_FLOATS:
            if key in it:
                it[key] = number(it[key], f"iterations[{i}].{key}")
        if not isinstance(it["gains"], list):
            raise FileError(f"{path}: iterations[{i}].gains is not a list")
        it["gains"] = _np.array([number(g, f"iterations[{i}].gains") for g in it["gains"]], dtype=_np.float64)
    return run


def __getattr__(name):
    """nbv.IgEvaluator, the class's name in 0.1.0: Decider, with a DeprecationWarning. It holds
    a planner's decider (the snapshot, the exhaustive table and the anytime decision), not only an
    evaluator; the old name goes in the next release."""
    if name == "IgEvaluator":
        import warnings
        warnings.warn("nbv.IgEvaluator is now nbv.Decider (the old name goes in the next release)", DeprecationWarning,
                      stacklevel=2)
        return Decider
    raise AttributeError(f"module 'nbv' has no attribute {name!r}")
