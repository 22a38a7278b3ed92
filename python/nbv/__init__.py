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
    table = nbv.IgEvaluator().evaluate(world, views, nbv.ray_set("released"), metrics=("pc",))
    best = int(table["pc"].argmax())
"""

from ._nbv import (  # noqa: F401  (the names users call)
    CapacityError,
    CloudFileError,
    DepthCamera,
    FileError,
    IgEvaluator,
    IgTable,
    InvalidArgument,
    MapFileError,
    Mesh,
    MeshFileError,
    OccupancyMap,
    SceneError,
    ViewFileError,
    __version__,
    dome48,
    fibonacci_sphere,
    isa,
    load_map,
    load_mesh,
    load_views,
    map_entropy_bits,
    ray_set,
    reconstruct,
    sample_surface,
    save_views,
    start_view,
    SurfaceCoverage,
    surface_coverage,
)

__all__ = [
    "CapacityError", "CloudFileError", "DepthCamera", "FileError", "IgEvaluator", "IgTable",
    "InvalidArgument", "MapFileError", "Mesh", "MeshFileError", "OccupancyMap", "SceneError",
    "ViewFileError", "dome48", "fibonacci_sphere", "isa", "load_map", "load_mesh", "load_views",
    "map_entropy_bits", "ray_set", "reconstruct", "sample_surface", "save_views", "start_view",
    "SurfaceCoverage", "surface_coverage",
]
