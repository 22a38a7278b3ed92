"""The functions and methods of the compiled module as users call them: each one's parameters,
their defaults, their kinds (nbv/_arguments.py) and what it returns, once. A docstring opens with
the signature written from these (nbv/_arguments.py), then the compiled one's text."""

from . import _nbv
from ._arguments import (ANY, BOOL, CALLABLE, COUNT, CROP, FLOAT, FLOATS, INT32, METRIC_NAMES, NAME, PATH, PLANNER, RAYS,
                         STR, UINT, VIEWSPACE, Kind, Refused, checked, instance, method, model, optional)

MAP = instance(_nbv.OccupancyMap, "an nbv.OccupancyMap (nbv.load_map reads a map file)")
CAMERA = optional(instance(_nbv.DepthCamera, "an nbv.DepthCamera"))
MODEL = model(_nbv.Mesh)


def _pose_not_camera(value):
    if isinstance(value, _nbv.DepthCamera):
        raise Refused(instead="is an nbv.DepthCamera: the pose comes second and the camera after it, "
                              "integrate_depth(depth, T_world_camera, camera=camera)")
    return value  # the compiled module reads and checks the pose


POSE = Kind("a pose", _pose_not_camera)

# The options of OccupancyMap(**config) and DepthCamera(**options), by name; their defaults are
# the compiled module's (the command line's).
MAP_OPTIONS = {name: FLOAT for name in _nbv._MAP_CONFIG_DEFAULTS if name != "resolution"}
CAMERA_OPTIONS = {"width": INT32, "height": INT32, "fx": FLOAT, "fy": FLOAT, "cx": FLOAT, "cy": FLOAT,
                  "max_range": FLOAT}
# The options of reconstruct() and experiment(): a scene preset's conditions hold unless
# ground_plane, no_return or crop is given, so these are options given by name, not defaults.
def _kinds(table):
    """The kinds of an option table of the compiled module (name -> (optional, default))."""
    return {name: optional(FLOAT) if is_optional else FLOAT for name, (is_optional, _) in table.items()}


RUN_OPTIONS = {**_kinds(_nbv._RECONSTRUCTION_OPTIONS),
               "weighting": STR, "threads": optional(INT32), "visibility": STR, "no_timings": BOOL, "scene": STR,
               "ground_plane": BOOL, "no_return": STR, "crop": CROP, "up": STR, "anytime": BOOL,
               **_kinds(_nbv._DECIDE_OPTIONS)}


@method(_nbv.OccupancyMap, MAP_OPTIONS)
def __init__(self, resolution: FLOAT = _nbv._MAP_CONFIG_DEFAULTS["resolution"], **config): ...


@method(_nbv.OccupancyMap)
def integrate(self, points: ANY, origin: ANY, discretize: BOOL = False) -> "dict": ...


@method(_nbv.OccupancyMap)
def integrate_depth(self, depth: ANY, T_world_camera: POSE, camera: CAMERA = None, scale: FLOAT = 5000.0,
                    no_return: STR = "drop", discretize: BOOL = False) -> "dict": ...


@method(_nbv.OccupancyMap)
def save(self, path: PATH): ...


@method(_nbv.OccupancyMap)
def probability(self, points: ANY) -> "(N,) float64": ...


@method(_nbv.OccupancyMap)
def log_odds(self, points: ANY) -> "(N,) float64": ...


@method(_nbv.Mesh)
def __init__(self, vertices: ANY, faces: ANY): ...  # noqa: F811 (each class's constructor)


@method(_nbv.DepthCamera, CAMERA_OPTIONS)
def __init__(self, **options): ...  # noqa: F811


@method(_nbv.DepthCamera)
def render(self, mesh: MODEL, T_world_camera: ANY, ground_plane: BOOL = False,
           labels: BOOL = False) -> "(depth (H, W) float32, points (K, 3) float32[, on_object (K,) bool])": ...


@method(_nbv.Decider)
def evaluate(self, map: MAP, views: ANY, rays: ANY, metrics: METRIC_NAMES = ("oa", "pc"), visibility: STR = "paper",
             max_ray_depth: FLOAT = _nbv._MAX_RAY_DEPTH, threads: optional(INT32) = None, reference: BOOL = False,
             seed: UINT = 0, isa: optional(STR) = None) -> "IgTable": ...


@method(_nbv.Decider)
def visible_voxels(self, map: MAP, view: ANY, rays: ANY, visibility: STR = "paper",
                   max_ray_depth: FLOAT = _nbv._MAX_RAY_DEPTH, threads: optional(INT32) = None) -> "dict": ...


@method(_nbv.Decider)
def decide(self, map: MAP, views: ANY, rays: ANY, metric: STR = "pc", weighting: STR = "normalized",
           gamma: FLOAT = 0.0, costs: optional(FLOATS) = None, epsilon: FLOAT = _nbv._DECIDE_OPTIONS["epsilon"][1],
           delta: FLOAT = _nbv._DECIDE_OPTIONS["delta"][1], max_rays: optional(UINT) = None,
           budget_ms: optional(FLOAT) = _nbv._DECIDE_OPTIONS["budget_ms"][1], seed: UINT = 0,
           visibility: STR = "paper", max_ray_depth: FLOAT = _nbv._MAX_RAY_DEPTH,
           threads: optional(INT32) = None) -> "dict": ...


@method(_nbv.SurfaceCoverage)
def __init__(self, ground_truth: ANY, d_reg: FLOAT = 0.005): ...  # noqa: F811


@method(_nbv.SurfaceCoverage)
def add_scan(self, observed: ANY): ...


@checked("load_map", _nbv.load_map, MAP_OPTIONS)
def load_map(path: PATH, max_map_mb: UINT = _nbv._MAX_MAP_MB, **config) -> "OccupancyMap": ...


@checked("load_mesh", _nbv.load_mesh)
def load_mesh(name_or_path: NAME, up: STR = "z") -> "Mesh": ...


@checked("fetch_models", _nbv.fetch_models)
def fetch_models(dir: optional(PATH) = None, source: optional(PATH) = None) -> "str": ...


@checked("sample_surface", _nbv.sample_surface)
def sample_surface(mesh: MODEL, count: UINT = _nbv._GROUND_TRUTH_POINTS, seed: UINT = 0) -> "(count, 3) float32": ...


@checked("ray_set", _nbv.ray_set)
def ray_set(rays: RAYS = "released") -> "(R, 3) float64": ...


@checked("fibonacci_sphere", _nbv.fibonacci_sphere)
def fibonacci_sphere(count: UINT, radius: FLOAT = 0.6, target: ANY = (0.0, 0.0, 0.25),
                     min_z: optional(FLOAT) = None) -> "(N, 4, 4) float64": ...


@checked("load_depth_png", _nbv.load_depth_png)
def load_depth_png(path: PATH) -> "(H, W) uint16": ...


@checked("load_frames", _nbv.load_frames)
def load_frames(folder: PATH,
                poses: optional(PATH) = None) -> "list of (path, T_world_camera (4, 4) float64)": ...


@checked("load_views", _nbv.load_views)
def load_views(path: PATH) -> "(N, 4, 4) float64": ...


@checked("save_views", _nbv.save_views)
def save_views(path: PATH, views: ANY): ...


@checked("reconstruct", _nbv.reconstruct, RUN_OPTIONS)
def reconstruct(model: MODEL, metric: PLANNER = "pc", seed: UINT = 0, iterations: COUNT = 20, rays: RAYS = "released",
                viewspace: VIEWSPACE = None, callback: optional(CALLABLE) = None, **options) -> "dict": ...


@checked("start_view", _nbv.start_view)
def start_view(seed: UINT, view_count: UINT) -> "int": ...


@checked("surface_coverage", _nbv.surface_coverage)
def surface_coverage(ground_truth: ANY, observed: ANY, d_reg: FLOAT = 0.005) -> "float": ...


@checked("map_entropy_bits", _nbv.map_entropy_bits)
def map_entropy_bits(map: MAP, centre: ANY, edge: FLOAT = 1.28) -> "float": ...


# models, metrics, trials and shard each take several types, which the compiled module tells
# apart and names.
@checked("experiment", _nbv.experiment, RUN_OPTIONS)
def experiment(models: ANY, metrics: ANY = "all", trials: ANY = 20, iterations: COUNT = 20, rays: RAYS = "released",
               viewspace: VIEWSPACE = None, callback: optional(CALLABLE) = None, out: optional(PATH) = None,
               shard: ANY = None, **options) -> "list": ...


@checked("table1", _nbv.table1)
def table1(runs: ANY) -> "str": ...


@checked("save_experiment", _nbv._results_csv)
def _results_csv(runs: ANY): ...
