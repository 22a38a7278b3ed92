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
#include <variant>

namespace nbv::python {

namespace {

py::array_t<double> affineArray(const Eigen::Affine3d& T) {
  std::vector<double> data(16);
  Eigen::Map<Eigen::Matrix<double, 4, 4, Eigen::RowMajor>>(data.data()) = T.matrix();
  return ownedArray(std::move(data), {4, 4});
}

/// The camera of the options given by name (the Python layer takes only the names read here
/// and gives each its type); each default is the command line's (the paper's camera).
sensor::DepthCameraConfig cameraConfig(const py::dict& options) {
  sensor::DepthCameraConfig c;
  for (const auto& [key, value] : options) {
    const std::string k = py::str(key);
    int* pixels = k == "width" ? &c.camera.width : k == "height" ? &c.camera.height : nullptr;
    double* number = k == "fx" ? &c.camera.fx : k == "fy" ? &c.camera.fy : k == "cx" ? &c.camera.cx
                   : k == "cy" ? &c.camera.cy : k == "max_range" ? &c.max_range_m : nullptr;
    if (pixels != nullptr) {
      *pixels = value.cast<int>();
    } else if (number != nullptr) {
      *number = value.cast<double>();
    } else {
      throw InvalidArgument("DepthCamera: unknown option '" + k + "'");
    }
  }
  c.camera.validate();
  return c;
}

/// A ray set's name, or a pixel stride.
sensor::PixelSampling samplingOf(const std::variant<int, std::string>& rays) {
  if (const std::string* name = std::get_if<std::string>(&rays)) return sensor::PixelSampling::fromName(*name);
  sensor::PixelSampling s{std::get<int>(rays), 1.0};
  s.validate();
  return s;
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

std::shared_ptr<Mesh> meshOf(const ModelGiven& model, const std::string& up) {
  if (const std::string* name = std::get_if<std::string>(&model)) return loadModel(*name, up);
  return std::get<std::shared_ptr<Mesh>>(model);
}

namespace {

constexpr const char* kMeshClassDoc = R"doc(
A triangle mesh in the world frame [m], with the ray-casting scene the depth camera renders
(built on first use, then shared).
)doc";
constexpr const char* kMeshDoc = R"doc(
vertices: (V, 3) floating, world frame [m], used as given (no normalisation). faces: (F, 3)
integer vertex indices, counter-clockwise. Raises nbv.InvalidArgument for bad shapes, dtypes or
indices.
)doc";
constexpr const char* kLoadMeshDoc = R"doc(
A standard model (bunny, armadillo, dragon, dino, head, bull, mannequin-devil, nefertiti, elk,
pig, diplodocus: fetch_models() fetches them; model_search_path() says where) or a mesh file
(OFF, PLY, OBJ, STL; others through assimp), placed as the command line places it
(docs/SEMANTICS.md, "Simulation and evaluation"): turned upright first if up="y" (the file's y
becomes z; up="auto": a standard model upright, a file as stored), largest side 0.5 m, centred on the z axis, lowest point at z = 0. `.transform` maps
the file's coordinates to these. Raises nbv.MeshFileError naming the file.
)doc";
constexpr const char* kFetchModelsDoc = R"doc(
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
Points spread uniformly by area over the mesh (an nbv.Mesh, or a model name or mesh file placed
as load_mesh() places it), world frame [m]: the ground truth of surface coverage. The same
mesh, count and seed give the same points.
)doc";
constexpr const char* kDepthCameraClassDoc = R"doc(
The ideal depth camera (docs/SEMANTICS.md, "Views and rays"): one exact ray per pixel through
the pinhole model, ray-cast against a mesh.
)doc";
constexpr const char* kDepthCameraDoc = R"doc(
Options and their defaults (the command line's): width 752, height 480 [pixels, 1 to 16384],
fx = fy = 448.1008985853343, cx 376.5, cy 240.5 [pixels], max_range 1.5 [m]. A negative fx or
fy flips that image axis (ICL-NUIM publishes fy = -480): docs/SEMANTICS.md "Views and rays".
)doc";
constexpr const char* kRenderDoc = R"doc(
Renders the mesh (an nbv.Mesh, or a model name or mesh file placed as load_mesh() places it)
from the camera pose T_world_camera ((4, 4) float64, camera -> world; optical
frame z forward, x along image columns, y along rows). depth: z-depth per pixel [m], 0 where the
pixel sees nothing within max_range. points: the world point [m] of every pixel that sees a
surface, in row-major pixel order; integrate them with the pose's translation as the origin.
ground_plane: the plane z = 0 joins the scene (docs/SEMANTICS.md, "Scene conditions"); with
labels=True a third array says which points lie on the mesh (only those cover it).
)doc";
constexpr const char* kRaySetDoc = R"doc(
The unit directions, camera frame, of an IG ray set of the default camera: "released" (stride 10
on the central 50 %: 950 rays), "released-shipped" (the 950 rays the released launch file casts,
its image sides swapped: docs/SEMANTICS.md "Views and rays"), "full" (every pixel: 360,960
rays) or a pixel stride N (an int).
)doc";
constexpr const char* kLoadDepthPngDoc = R"doc(
A 16-bit greyscale PNG depth image as its raw values (docs/SEMANTICS.md, "Real sensor input"),
for OccupancyMap.integrate_depth with the dataset's scale (TUM RGB-D and ICL-NUIM: 5000 per
metre). Raises nbv.FileError naming the file for anything else.
)doc";
constexpr const char* kLoadFramesDoc = R"doc(
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
`count` views on a sphere of `radius` [m] around `target` (world frame [m]), spread by the
golden-angle lattice, each looking at the target with the dome's roll. min_z [m] leaves out the
views below that height (N <= count).
)doc";
constexpr const char* kLoadViewsDoc = R"doc(
Reads a view file (`N`, then N lines `x y z qx qy qz qw`). Raises nbv.ViewFileError naming the
file and line.
)doc";
constexpr const char* kSaveViewsDoc = R"doc(
Writes (N, 4, 4) T_world_camera poses as a view file that load_views() and the command line read.
)doc";

}  // namespace

namespace {

void bindMeshes(py::module_& m) {
  py::class_<Mesh, std::shared_ptr<Mesh>>(m, "Mesh", kMeshClassDoc)
      .def(py::init([](const py::handle& vertices, const py::handle& faces) {
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
           kMeshDoc)
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
      [](const std::string& name_or_path, const std::string& up) { return loadModel(name_or_path, up); },
      kLoadMeshDoc);
}

void bindModelsCameraAndRays(py::module_& m) {

  m.def(
      "fetch_models",
      [](const std::optional<std::filesystem::path>& dir, const std::optional<std::filesystem::path>& source) {
        sensor::FetchOptions options;
        if (dir) options.dir = *dir;
        if (source) options.source = *source;
        py::gil_scoped_release unlocked;
        return sensor::fetchStandardModels(options).dir.string();
      },
      kFetchModelsDoc);

  m.def(
      "model_search_path", [] {
        py::list dirs;
        for (const std::filesystem::path& dir : sensor::modelSearchPath()) dirs.append(dir.string());
        return dirs;
      },
      kModelSearchPathDoc);

  m.attr("_GROUND_TRUTH_POINTS") = sensor::kDefaultGroundTruthPoints;  // sample_surface()'s default count
  m.def(
      "sample_surface",
      [](const ModelGiven& mesh, std::size_t count, std::uint64_t seed) {
        return ownedRows(sensor::sampleSurface(meshOf(mesh, "z")->mesh(), count, seed));
      },
      kSampleSurfaceDoc);

  py::class_<sensor::DepthCamera>(m, "DepthCamera", kDepthCameraClassDoc)
      .def(py::init([](const py::dict& options) { return sensor::DepthCamera(cameraConfig(options)); }),
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
          [](const sensor::DepthCamera& camera, const ModelGiven& model, const py::handle& T_world_camera,
             bool ground_plane, bool labels) {
            const std::shared_ptr<Mesh> loaded = meshOf(model, "z");
            const Mesh& mesh = *loaded;
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
          kRenderDoc);

  m.def(
      "ray_set",
      [](const std::variant<int, std::string>& rays) {
        return ownedRows(sensor::rayDirectionsCamera(sensor::PinholeCamera{}, samplingOf(rays)));
      },
      kRaySetDoc);

  m.def("dome48", [] { return posesArray(planner::dome48()); }, kDome48Doc);
}

void bindViewspaces(py::module_& m) {

  m.def(
      "fibonacci_sphere",
      [](std::size_t count, double radius, const py::handle& target, std::optional<double> min_z) {
        std::vector<planner::View> views = planner::fibonacciSphere(count, radius, vector3(target, "target"));
        if (min_z) views = planner::viewsAbove(views, *min_z);
        return posesArray(views);
      },
      kFibonacciSphereDoc);

  m.def(
      "load_depth_png",
      [](const std::filesystem::path& path) {
        sensor::DepthPng png = sensor::readDepthPng16(path);
        return ownedArray(std::move(png.values), {png.height, png.width});
      },
      kLoadDepthPngDoc);
  m.def(
      "load_frames",
      [](const std::filesystem::path& folder, const std::optional<std::filesystem::path>& poses) {
        const std::vector<sensor::TumFrame> frames =
            poses ? sensor::readFrameFolder(folder, *poses) : sensor::readTumSequence(folder);
        py::list out;
        for (const sensor::TumFrame& f : frames) {
          out.append(py::make_tuple(f.depth_file.string(), affineArray(Eigen::Affine3d(f.T_world_camera.matrix()))));
        }
        return out;
      },
      kLoadFramesDoc);
  m.def(
      "load_views",
      [](const std::filesystem::path& path) { return posesArray(planner::loadViews(path)); }, kLoadViewsDoc);

  m.def(
      "save_views",
      [](const std::filesystem::path& path, const py::handle& views) { planner::saveViews(path, viewsOf(views, "views")); },
      kSaveViewsDoc);
}

}  // namespace

void bindSensor(py::module_& m) {
  bindMeshes(m);
  bindModelsCameraAndRays(m);
  bindViewspaces(m);
}

}  // namespace nbv::python
