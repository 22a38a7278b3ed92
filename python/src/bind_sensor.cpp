// Meshes, the depth camera, ray sets and viewspaces.
#include "arrays.hpp"
#include "bindings.hpp"
#include "threads.hpp"

#include "nbv/errors.hpp"
#include "nbv/planner/viewspace.hpp"
#include "nbv/sensor/depth_io.hpp"
#include "nbv/sensor/pinhole_camera.hpp"
#include "nbv/sensor/models.hpp"
#include "nbv/sensor/surface_sampling.hpp"

#include <pybind11/stl.h>
#include <pybind11/stl/filesystem.h>

#include <cstdlib>
#include <mutex>

namespace nbv::python {

namespace {

py::array_t<double> affineArray(const Eigen::Affine3d& T) {
  std::vector<double> data(16);
  Eigen::Map<Eigen::Matrix<double, 4, 4, Eigen::RowMajor>>(data.data()) = T.matrix();
  return ownedArray(std::move(data), {4, 4});
}

/// The camera of keyword arguments; each default is the command line's (the paper's camera).
sensor::DepthCameraConfig cameraConfig(const py::kwargs& options) {
  sensor::DepthCameraConfig c;
  const KeywordOptions option{"DepthCamera"};
  for (const auto& [key, value] : options) {
    const std::string k = py::str(key);
    if (k == "width") {
      c.camera.width = option.as<int>(value, k);
    } else if (k == "height") {
      c.camera.height = option.as<int>(value, k);
    } else if (k == "fx") {
      c.camera.fx = option.as<double>(value, k);
    } else if (k == "fy") {
      c.camera.fy = option.as<double>(value, k);
    } else if (k == "cx") {
      c.camera.cx = option.as<double>(value, k);
    } else if (k == "cy") {
      c.camera.cy = option.as<double>(value, k);
    } else if (k == "max_range") {
      c.max_range_m = option.as<double>(value, k);
    } else {
      option.refuse(k, "width, height, fx, fy, cx, cy, max_range");
    }
  }
  c.camera.validate();
  return c;
}

sensor::PixelSampling samplingOf(const py::handle& rays) {
  if (py::isinstance<py::str>(rays)) return sensor::PixelSampling::fromName(rays.cast<std::string>());
  if (py::isinstance<py::int_>(rays) && !py::isinstance<py::bool_>(rays)) {
    sensor::PixelSampling s{optionValue<int>(rays, "rays"), 1.0};
    s.validate();
    return s;
  }
  throw InvalidArgument("rays: give 'released', 'released-shipped', 'full' or a pixel stride (an int), not " +
                        std::string(py::str(py::type::of(rays).attr("__name__"))));
}

}  // namespace

std::shared_ptr<Mesh> loadModel(const std::string& name_or_path, const std::string& up) {
  const std::filesystem::path path = sensor::resolveModel(name_or_path);
  const sensor::UpAxis axis = sensor::upAxisFor(name_or_path, up);
  const bool standard = path.string() != name_or_path;  // a short name resolved to its file
  const std::string source = standard ? name_or_path : std::filesystem::absolute(path).lexically_normal().string();
  // The meshes loaded last, by file, its time and the up axis: meshes are immutable once made.
  struct Loaded {
    std::string file;
    std::filesystem::file_time_type time;
    sensor::UpAxis axis;
    std::shared_ptr<Mesh> mesh;
  };
  static std::mutex mutex;
  static std::vector<Loaded> recent;
  std::error_code ec;
  const auto time = std::filesystem::last_write_time(path, ec);
  const std::string file = std::filesystem::absolute(path).string();
  {
    const std::lock_guard<std::mutex> lock(mutex);
    for (const Loaded& l : recent) {
      if (l.file == file && l.time == time && l.axis == axis && l.mesh->source() == source) return l.mesh;
    }
  }
  sensor::TriangleMesh mesh = sensor::loadMesh(path);
  const sensor::Normalization n = sensor::normalizeMesh(mesh, {axis});
  auto loaded = std::make_shared<Mesh>(std::move(mesh), n.T_normalized_original, source, up);
  const std::lock_guard<std::mutex> lock(mutex);
  constexpr std::size_t kKept = 4;
  if (recent.size() == kKept) recent.erase(recent.begin());
  recent.push_back({file, time, axis, loaded});
  return loaded;
}

std::shared_ptr<Mesh> meshOf(const py::handle& model, const std::string& up, const std::string& where) {
  if (const std::optional<std::string> name = modelNameOrPath(model)) return loadModel(*name, up);
  if (!py::isinstance<Mesh>(model)) {
    throw InvalidArgument(where + " = " + shortRepr(model) + " is not a model name, a mesh file or an nbv.Mesh");
  }
  return model.cast<std::shared_ptr<Mesh>>();
}

const grid::OccupancyMap& mapOf(const py::handle& map, const std::string& where) {
  if (!py::isinstance<grid::OccupancyMap>(map)) {
    throw InvalidArgument(where + ": map = " + shortRepr(map) + " is not an nbv.OccupancyMap (nbv.load_map reads a map file)");
  }
  return map.cast<const grid::OccupancyMap&>();
}

std::filesystem::path pathOf(const py::handle& value, const std::string& where) {
  if (py::isinstance<py::str>(value) || py::hasattr(value, "__fspath__")) {
    const py::object path = py::module_::import("os").attr("fspath")(value);
    if (py::isinstance<py::str>(path)) return path.cast<std::string>();
  }
  throw InvalidArgument(where + " = " + shortRepr(value) + " is not a file's path (a str or an os.PathLike)");
}

std::optional<std::string> modelNameOrPath(const py::handle& value) {
  if (py::isinstance<py::str>(value)) return value.cast<std::string>();
  if (py::hasattr(value, "__fspath__")) {
    const py::object path = py::module_::import("os").attr("fspath")(value);
    if (py::isinstance<py::str>(path)) return path.cast<std::string>();
  }
  return std::nullopt;
}

namespace {

constexpr const char* kMeshClassDoc = R"doc(
A triangle mesh in the world frame [m], with the ray-casting scene the depth camera renders
(built on first use, then shared).
)doc";
constexpr const char* kMeshDoc = R"doc(
Mesh(vertices, faces)

vertices: (V, 3) floating, world frame [m], used as given (no normalisation). faces: (F, 3)
integer vertex indices, counter-clockwise. Raises nbv.InvalidArgument for bad shapes, dtypes or
indices.
)doc";
constexpr const char* kLoadMeshDoc = R"doc(
load_mesh(name_or_path, up="z") -> Mesh

A standard model (bunny, armadillo, dragon, dino, head, bull, mannequin-devil, nefertiti, elk,
pig, diplodocus: fetch_models() fetches them; model_search_path() says where) or a mesh file
(OFF, PLY, OBJ, STL; others through assimp), placed as the command line places it
(docs/SEMANTICS.md, "Simulation and evaluation"): turned upright first if up="y" (the file's y
becomes z; up="auto": a standard model upright, a file as stored), largest side 0.5 m, centred on the z axis, lowest point at z = 0. `.transform` maps
the file's coordinates to these. Raises nbv.MeshFileError naming the file.
)doc";
constexpr const char* kFetchModelsDoc = R"doc(
fetch_models(dir=None, source=None) -> str

Puts the 11 standard meshes into `dir` (None: the user's data folder, $XDG_DATA_HOME/nbv/models
or ~/.local/share/nbv/models, or NBV_MODELS_DIR if set) from the data archive of Debian's
libcgal-demo, as `nbv models fetch` does: `source` names its .deb or data.tar.gz, else the
installed package's archive, apt's cached .deb or `apt-get download` is used. Files already
there are kept. Returns the folder. Raises nbv.FileError with what failed.
)doc";
constexpr const char* kModelSearchPathDoc = R"doc(
model_search_path() -> list of str

The folders a standard model's name is looked for in, in order: NBV_MODELS_DIR alone if set;
else the user's data folder (where fetch_models() writes), then each of $XDG_DATA_DIRS
(default /usr/local/share, /usr/share) followed by nbv/models.
)doc";
constexpr const char* kSampleSurfaceDoc = R"doc(
sample_surface(mesh, count=200000, seed=0) -> (count, 3) float32

Points spread uniformly by area over the mesh (an nbv.Mesh, or a model name or mesh file placed
as load_mesh() places it), world frame [m]: the ground truth of surface coverage. The same
mesh, count and seed give the same points.
)doc";
constexpr const char* kDepthCameraClassDoc = R"doc(
The ideal depth camera (docs/SEMANTICS.md, "Views and rays"): one exact ray per pixel through
the pinhole model, ray-cast against a mesh.
)doc";
constexpr const char* kDepthCameraDoc = R"doc(
DepthCamera(**options)

Options and their defaults (the command line's): width 752, height 480 [pixels, 1 to 16384],
fx = fy = 448.1008985853343, cx 376.5, cy 240.5 [pixels], max_range 1.5 [m]. A negative fx or
fy flips that image axis (ICL-NUIM publishes fy = -480): docs/SEMANTICS.md "Views and rays".
)doc";
constexpr const char* kRenderDoc = R"doc(
render(mesh, T_world_camera, ground_plane=False, labels=False)
    -> (depth (H, W) float32, points (K, 3) float32[, on_object (K,) bool])

Renders the mesh (an nbv.Mesh, or a model name or mesh file placed as load_mesh() places it)
from the camera pose T_world_camera ((4, 4) float64, camera -> world; optical
frame z forward, x along image columns, y along rows). depth: z-depth per pixel [m], 0 where the
pixel sees nothing within max_range. points: the world point [m] of every pixel that sees a
surface, in row-major pixel order; integrate them with the pose's translation as the origin.
ground_plane: the plane z = 0 joins the scene (docs/SEMANTICS.md, "Scene conditions"); with
labels=True a third array says which points lie on the mesh (only those cover it).
)doc";
constexpr const char* kRaySetDoc = R"doc(
ray_set(rays="released") -> (R, 3) float64

The unit directions, camera frame, of an IG ray set of the default camera: "released" (stride 10
on the central 50 %: 950 rays), "released-shipped" (the 950 rays the released launch file casts,
its image sides swapped: docs/SEMANTICS.md "Views and rays"), "full" (every pixel: 360,960
rays) or a pixel stride N (an int).
)doc";
constexpr const char* kLoadDepthPngDoc = R"doc(
load_depth_png(path) -> (H, W) uint16

A 16-bit greyscale PNG depth image as its raw values (docs/SEMANTICS.md, "Real sensor input"),
for OccupancyMap.integrate_depth with the dataset's scale (TUM RGB-D and ICL-NUIM: 5000 per
metre). Raises nbv.FileError naming the file for anything else.
)doc";
constexpr const char* kLoadFramesDoc = R"doc(
load_frames(folder, poses=None) -> list of (path, T_world_camera (4, 4) float64)

A dataset's depth frames in order, each its image's path and its camera pose: with poses None,
a TUM RGB-D folder (depth.txt, groundtruth.txt; each frame takes the pose nearest in time,
within 20 ms); else a folder of numbered PNGs, ordered by the last number in their names, and
`poses`, a file of one `tx ty tz qx qy qz qw` per frame (docs/SEMANTICS.md, "Real sensor
input"). Raises nbv.FileError naming the file and line.
)doc";
constexpr const char* kDome48Doc = R"doc(
dome48() -> (48, 4, 4) float64

The paper's 48 candidate views as T_world_camera poses (docs/SEMANTICS.md, "The planner").
)doc";
constexpr const char* kFibonacciSphereDoc = R"doc(
fibonacci_sphere(count, radius=0.6, target=(0, 0, 0.25), min_z=None) -> (N, 4, 4) float64

`count` views on a sphere of `radius` [m] around `target` (world frame [m]), spread by the
golden-angle lattice, each looking at the target with the dome's roll. min_z [m] leaves out the
views below that height (N <= count).
)doc";
constexpr const char* kLoadViewsDoc = R"doc(
load_views(path) -> (N, 4, 4) float64

Reads a view file (`N`, then N lines `x y z qx qy qz qw`). Raises nbv.ViewFileError naming the
file and line.
)doc";
constexpr const char* kSaveViewsDoc = R"doc(
save_views(path, views)

Writes (N, 4, 4) T_world_camera poses as a view file that load_views() and the command line read.
)doc";

}  // namespace

namespace {

void bindMeshes(py::module_& m) {
  py::class_<Mesh, std::shared_ptr<Mesh>>(m, "Mesh", kMeshClassDoc)
      .def(py::init([](const py::object& vertices, const py::object& faces) {
             const Rows<Eigen::Vector3f> v = pointsFloat(vertices, "vertices");
             const py::array f = py::array::ensure(faces);
             if (!f || f.dtype().kind() != 'i' || f.ndim() != 2 || f.shape(1) != 3) {
               throw InvalidArgument("faces: give an (F, 3) integer array of vertex indices");
             }
             const auto indices = py::array_t<long long, py::array::c_style | py::array::forcecast>::ensure(f);
             sensor::TriangleMesh mesh;
             mesh.vertices.assign(v.rows.begin(), v.rows.end());
             for (py::ssize_t i = 0; i < indices.shape(0); ++i) {
               Eigen::Vector3i t;
               for (int k = 0; k < 3; ++k) {
                 const long long index = indices.at(i, k);
                 if (index < 0 || index >= static_cast<long long>(mesh.vertices.size())) {
                   throw InvalidArgument("faces[" + std::to_string(i) + "] has vertex index " + std::to_string(index) +
                                         ", outside [0, " + std::to_string(mesh.vertices.size()) + ")");
                 }
                 t[k] = static_cast<int>(index);
               }
               mesh.triangles.push_back(t);
             }
             if (mesh.triangles.empty()) throw InvalidArgument("faces: the mesh has no triangle");
             return std::make_shared<Mesh>(std::move(mesh), Eigen::Affine3d::Identity());
           }),
           py::arg("vertices"), py::arg("faces"), kMeshDoc)
      .def_property_readonly("vertices", [](const Mesh& mesh) {
             auto v = mesh.mesh().vertices;
             return ownedRows(std::move(v));
           },
           "(V, 3) float32 vertices, world frame [m] (a copy).")
      .def_property_readonly("faces", [](const Mesh& mesh) {
             std::vector<std::int32_t> f;
             for (const Eigen::Vector3i& t : mesh.mesh().triangles) f.insert(f.end(), {t.x(), t.y(), t.z()});
             return ownedArray(std::move(f), {static_cast<py::ssize_t>(mesh.mesh().triangles.size()), 3});
           },
           "(F, 3) int32 vertex indices (a copy).")
      .def_property_readonly("transform", [](const Mesh& mesh) { return affineArray(mesh.transform()); },
                             "(4, 4) float64: mesh file coordinates -> these vertices (load_mesh's normalisation); "
                             "its inverse maps results back to the file's frame.")
      .def_property_readonly("bounds", [](const Mesh& mesh) {
             const Eigen::AlignedBox3d box = sensor::meshBounds(mesh.mesh());
             std::vector<double> lo(box.min().data(), box.min().data() + 3), hi(box.max().data(), box.max().data() + 3);
             return py::make_tuple(ownedArray(std::move(lo), {3}), ownedArray(std::move(hi), {3}));
           },
           "(lo, hi): (3,) float64 corners of the vertices' bounding box [m].")
      .def_property_readonly("source", [](const Mesh& mesh) -> py::object {
             return mesh.source().empty() ? py::object(py::none()) : py::object(py::str(mesh.source()));
           },
           "What the mesh was loaded from: a standard model's name or a file's absolute path (which a saved "
           "run names), or None for a mesh of arrays.")
      .def("__repr__", [](const Mesh& mesh) {
        return "<nbv.Mesh " + std::to_string(mesh.mesh().vertices.size()) + " vertices, " +
               std::to_string(mesh.mesh().triangles.size()) + " triangles>";
      });

  m.def(
      "load_mesh",
      [](const py::object& name_or_path, const py::object& up) {
        const std::optional<std::string> name = modelNameOrPath(name_or_path);
        if (!name) {
          throw InvalidArgument("load_mesh: name_or_path = " + shortRepr(name_or_path) +
                                " is not a model name or a mesh file's path (a str or an os.PathLike)");
        }
        return loadModel(*name, optionValue<std::string>(up, "load_mesh: up"));
      },
      py::arg("name_or_path"), py::arg("up") = "z", kLoadMeshDoc);
}

void bindModelsCameraAndRays(py::module_& m) {

  m.def(
      "fetch_models",
      [](const py::object& dir, const py::object& source) {
        sensor::FetchOptions options;
        if (!dir.is_none()) options.dir = pathOf(dir, "fetch_models: dir");
        if (!source.is_none()) options.source = pathOf(source, "fetch_models: source");
        py::gil_scoped_release unlocked;
        return sensor::fetchStandardModels(options).dir.string();
      },
      py::arg("dir") = py::none(), py::arg("source") = py::none(), kFetchModelsDoc);

  m.def(
      "model_search_path", [] {
        py::list dirs;
        for (const std::filesystem::path& dir : sensor::modelSearchPath()) dirs.append(dir.string());
        return dirs;
      },
      kModelSearchPathDoc);

  m.def(
      "sample_surface",
      [](const py::object& mesh, const py::object& count, const py::object& seed) {
        const KeywordOptions option{"sample_surface"};
        const std::shared_ptr<Mesh> model = meshOf(mesh, "z", "sample_surface: mesh");
        return ownedRows(sensor::sampleSurface(model->mesh(), option.as<std::size_t>(count, "count"),
                                               option.as<std::uint64_t>(seed, "seed")));
      },
      py::arg("mesh"), py::arg("count") = sensor::kDefaultGroundTruthPoints, py::arg("seed") = 0, kSampleSurfaceDoc);

  py::class_<sensor::DepthCamera>(m, "DepthCamera", kDepthCameraClassDoc)
      .def(py::init([](const py::kwargs& options) { return sensor::DepthCamera(cameraConfig(options)); }),
           kDepthCameraDoc)
      .def_property_readonly("width", [](const sensor::DepthCamera& c) { return c.config().camera.width; })
      .def_property_readonly("height", [](const sensor::DepthCamera& c) { return c.config().camera.height; })
      .def_property_readonly("fx", [](const sensor::DepthCamera& c) { return c.config().camera.fx; })
      .def_property_readonly("fy", [](const sensor::DepthCamera& c) { return c.config().camera.fy; })
      .def_property_readonly("cx", [](const sensor::DepthCamera& c) { return c.config().camera.cx; })
      .def_property_readonly("cy", [](const sensor::DepthCamera& c) { return c.config().camera.cy; })
      .def_property_readonly("max_range", [](const sensor::DepthCamera& c) { return c.config().max_range_m; })
      .def(
          "render",
          [](const sensor::DepthCamera& camera, const py::object& model, const py::object& T_world_camera,
             const py::object& ground_plane_arg, const py::object& labels_arg) {
            const KeywordOptions option{"DepthCamera.render"};
            const std::shared_ptr<Mesh> loaded = meshOf(model, "z", option.owner + ": mesh");
            const Mesh& mesh = *loaded;
            const bool ground_plane = option.as<bool>(ground_plane_arg, "ground_plane");
            const bool labels = option.as<bool>(labels_arg, "labels");
            const Eigen::Isometry3d T = pose(T_world_camera, "T_world_camera");
            sensor::DepthScan scan = runReleased(std::nullopt,
                                                 [&] { return camera.render(mesh.scene(ground_plane), T); });
            auto depth = ownedArray(std::move(scan.depth_m), {scan.height, scan.width});
            if (!labels) return py::make_tuple(depth, ownedRows(std::move(scan.points_world)));
            std::vector<bool> object;
            for (const sensor::Surface s : scan.surfaces) object.push_back(s == sensor::Surface::Object);
            py::array_t<bool> on_object(static_cast<py::ssize_t>(object.size()));
            for (std::size_t i = 0; i < object.size(); ++i) on_object.mutable_at(static_cast<py::ssize_t>(i)) = object[i];
            return py::make_tuple(depth, ownedRows(std::move(scan.points_world)), on_object);
          },
          py::arg("mesh"), py::arg("T_world_camera"), py::arg("ground_plane") = false, py::arg("labels") = false, kRenderDoc);

  m.def(
      "ray_set",
      [](const py::object& rays) {
        auto directions = sensor::rayDirectionsCamera(sensor::PinholeCamera{}, samplingOf(rays));
        return ownedRows(std::move(directions));
      },
      py::arg("rays") = "released", kRaySetDoc);

  m.def("dome48", [] { return posesArray(planner::dome48()); }, kDome48Doc);
}

void bindViewspaces(py::module_& m) {

  m.def(
      "fibonacci_sphere",
      [](const py::object& count, const py::object& radius, const py::object& target, const py::object& min_z_arg) {
        const KeywordOptions option{"fibonacci_sphere"};
        const auto min_z = option.as<std::optional<double>>(min_z_arg, "min_z");
        std::vector<planner::View> views = planner::fibonacciSphere(
            option.as<std::size_t>(count, "count"), option.as<double>(radius, "radius"), vector3(target, "target"));
        if (min_z) views = planner::viewsAbove(views, *min_z);
        return posesArray(views);
      },
      py::arg("count"), py::arg("radius") = 0.6, py::arg("target") = py::make_tuple(0.0, 0.0, 0.25),
      py::arg("min_z") = py::none(), kFibonacciSphereDoc);

  m.def(
      "load_depth_png",
      [](const py::object& path) {
        sensor::DepthPng png = sensor::readDepthPng16(pathOf(path, "load_depth_png: path"));
        return ownedArray(std::move(png.values), {png.height, png.width});
      },
      py::arg("path"), kLoadDepthPngDoc);
  m.def(
      "load_frames",
      [](const py::object& folder, const py::object& poses) {
        const std::filesystem::path dir = pathOf(folder, "load_frames: folder");
        const std::vector<sensor::TumFrame> frames =
            poses.is_none() ? sensor::readTumSequence(dir) : sensor::readFrameFolder(dir, pathOf(poses, "load_frames: poses"));
        py::list out;
        for (const sensor::TumFrame& f : frames) {
          out.append(py::make_tuple(f.depth_file.string(), affineArray(Eigen::Affine3d(f.T_world_camera.matrix()))));
        }
        return out;
      },
      py::arg("folder"), py::arg("poses") = py::none(), kLoadFramesDoc);
  m.def(
      "load_views",
      [](const py::object& path) { return posesArray(planner::loadViews(pathOf(path, "load_views: path"))); },
      py::arg("path"),
      kLoadViewsDoc);

  m.def(
      "save_views", [](const py::object& path, const py::object& views) {
        planner::saveViews(pathOf(path, "save_views: path"), viewsOf(views, "views"));
      },
      py::arg("path"), py::arg("views"), kSaveViewsDoc);
}

}  // namespace

void bindSensor(py::module_& m) {
  bindMeshes(m);
  bindModelsCameraAndRays(m);
  bindViewspaces(m);
}

}  // namespace nbv::python
