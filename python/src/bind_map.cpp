// nbv.OccupancyMap and the map files.
#include "arrays.hpp"
#include "bindings.hpp"

#include "nbv/errors.hpp"
#include "nbv/grid/map_io.hpp"
#include "nbv/sensor/depth_camera.hpp"

#include <pybind11/stl.h>
#include <pybind11/stl/filesystem.h>

#include <map>
#include <optional>

namespace nbv::python {

namespace {

using grid::OccupancyMap;

/// The map configuration: the resolution and the options given by name, the rows of
/// grid::NBV_MAP_CONFIG_FIELDS (the Python layer takes only those names).
grid::MapConfig mapConfig(double resolution, const std::map<std::string, double>& given) {
  grid::MapConfig c;
  c.resolution = resolution;
  for (const auto& [key, value] : given) {
    const grid::MapConfigField* field = grid::mapConfigField(key);
    if (field == nullptr || key == "resolution") throw InvalidArgument("OccupancyMap: unknown option '" + key + "'");
    c.*field->member = value;
  }
  return c;
}

py::dict configDict(const grid::MapConfig& c) {
  py::dict d;
  for (const grid::MapConfigField& f : grid::mapConfigFields()) d[f.name] = c.*f.member;
  return d;
}

/// The fields as a docstring lists them, a line each: "  p_hit = 0.7: occupancy probability
/// of a hit; must be in (0.5, 1)".
std::string mapOptionsHelp() {
  std::string help;
  for (const grid::MapConfigField& f : grid::mapConfigFields()) {
    const std::string unit = *f.unit ? std::string(" [") + f.unit + "]" : "";
    help += "  " + std::string(f.name) + unit + " = " + numberText(f.default_value) + ": " + f.help + "; " + f.rule + "\n";
  }
  return help;
}

/// One value per point of an (N, 3) array, read at the voxel holding it.
template <class F>
py::array_t<double> perPoint(const OccupancyMap& map, const py::handle& points, F value) {
  const Rows<Eigen::Vector3d> p = pointsDouble(points, "points");
  std::vector<double> out(p.rows.size());
  for (std::size_t i = 0; i < out.size(); ++i) {
    if (!p.rows[i].allFinite()) throw InvalidArgument("points[" + std::to_string(i) + "] is not finite");
    if (!map.lattice().inRange(p.rows[i])) throw InvalidArgument("points[" + std::to_string(i) + "] is outside the map's index range");
    out[i] = value(map.worldToIndex(p.rows[i]));
  }
  return ownedArray(std::move(out), {static_cast<py::ssize_t>(p.rows.size())});
}

/// The counts of one scan into `map`, after a Python warning (UserWarning) if most of its
/// points lay beyond the map's range.
py::dict scanResult(const OccupancyMap& map, const grid::ScanStats& stats);

py::dict statsDict(const grid::ScanStats& s) {
  py::dict d;
  d["points"] = s.points;
  d["skipped_points"] = s.skipped_points;
  d["hits"] = s.hits;
  d["beyond_range"] = s.beyond_range;
  d["too_near"] = s.too_near;
  d["voxels_hit"] = s.voxels_hit;
  d["voxels_missed"] = s.voxels_missed;
  d["voxels_marked"] = s.voxels_marked;
  return d;
}

py::dict scanResult(const OccupancyMap& map, const grid::ScanStats& stats) {
  if (const std::string warning = grid::beyondRangeWarning(stats, map.config()); !warning.empty()) {
    if (PyErr_WarnEx(PyExc_UserWarning, warning.c_str(), 2) != 0) throw py::error_already_set();
  }
  return statsDict(stats);
}

}  // namespace

namespace {

constexpr const char* kOccupancyMapClassDoc = R"doc(
The probabilistic voxel map (docs/SEMANTICS.md, "The map"): log-odds occupancy per voxel of an
OpenVDB grid, plus the proximity marks of Proximity Count and Area Factor. The same scans give
the voxels and log-odds OctoMap gives. Voxel (i, j, k) is centred at ((i, j, k) + 0.5) *
resolution, in metres, world frame.

Thread-safety: queries may run concurrently; integrate() needs the map to itself.
)doc";
/// OccupancyMap()'s docstring, its options from the table.
const std::string& occupancyMapDoc() {
  static const std::string doc = R"doc(
The resolution, then config by name (docs/SEMANTICS.md, "The map"):
)doc" + mapOptionsHelp() + R"doc(Raises nbv.InvalidArgument for an unknown key or a bad value.
)doc";
  return doc;
}
constexpr const char* kIntegrateDoc = R"doc(
Integrates one scan as OctoMap's insertPointCloud (docs/SEMANTICS.md, "The map"), then sets
the proximity marks. discretize=True: as OctoMap's discretize option, one ray per distinct
voxel the points end in, to its centre (far fewer rays for a dense scan; another map).
points: (N, 3) float32 or float64, world frame [m] (read in place, without a copy, when
C-contiguous float32; otherwise converted once); non-finite rows are skipped. origin: (3,)
sensor position, world frame [m]. A cloud with no finite point raises nbv.InvalidArgument.
Returns the counts of the scan: points, skipped_points, hits, beyond_range, too_near,
voxels_hit, voxels_missed, voxels_marked. Runs on TBB threads with the GIL released.
)doc";
constexpr const char* kIntegrateDepthDoc = R"doc(
Integrates one depth frame (docs/SEMANTICS.md, "Real sensor input") as the cloud it stands for:
depth (H, W) uint16 (raw values, `scale` per metre: TUM RGB-D's 5000) or float32/float64
(metres), z-depth per pixel, 0 or NaN for no return. T_world_camera: (4, 4) float64 camera ->
world (the data, then the pose, as integrate() and DepthCamera.render() take them). camera: an
nbv.DepthCamera whose intrinsics took the image (None: the default 752 x 480 camera). no_return: "drop", or "clear" (free space up to the map's max_range). Returns
the counts of integrate().
)doc";
constexpr const char* kSaveDoc = R"doc(
Writes the map as .vdb (everything), .ot (log-odds, no proximity marks) or .bt (occupied/free
only), by the extension. Raises nbv.MapFileError (an OSError) naming the file.
)doc";
constexpr const char* kCountsDoc = R"doc(
counts() -> dict

Voxel counts: measured; occupied (P > occupied_threshold), free (P < free_threshold) and unknown
among them, the classes of the metrics; octomap_occupied (log-odds >= 0, OctoMap's
isNodeOccupied); marked (proximity marks).
)doc";
constexpr const char* kBoundsDoc = R"doc(
bounds() -> (lo, hi) or None

World bounds [m] of the measured voxels (outer faces): two (3,) float64 arrays; None if no voxel
is measured.
)doc";
constexpr const char* kProbabilityDoc = R"doc(
Occupancy probability of the voxel holding each point; points (N, 3) floating, world frame [m].
0.5 where no scan has measured the voxel.
)doc";
constexpr const char* kLogOddsDoc = R"doc(
Log-odds of the voxel holding each point (0 where unmeasured); points (N, 3) floating, world
frame [m].
)doc";
constexpr const char* kMeasuredVoxelsDoc = R"doc(
measured_voxels() -> (centres (K, 3) float64 [m], log_odds (K,) float32)

Every measured voxel, sorted by index (i, j, k): its centre in the world frame and its log-odds.
)doc";
constexpr const char* kProximityMarksDoc = R"doc(
proximity_marks() -> (centres (K, 3) float64 [m], distances (K,) int32)

Every proximity mark, sorted by index: the voxel's centre and its distance behind a surface in
voxel steps.
)doc";
constexpr const char* kLoadMapDoc = R"doc(
Reads a .vdb, .ot or .bt map (by extension). A .vdb holds its sensor model and ranges; an OctoMap
file holds only the resolution, and its map takes config (the options of OccupancyMap: p_hit,
clamp_min, max_range, ... ; max_range is the range of the scans you will integrate into it) and
has no proximity marks. OctoMap's ColorOcTree and OcTreeStamped files are read too (a UserWarning
says what the map drops: the colours). Pruned nodes stay one tile each (docs/SEMANTICS.md, "The
map"). Raises nbv.MapFileError naming the file for a missing, truncated or malformed one, or one
whose map would take more than max_map_mb MiB; nbv.InvalidArgument for an unknown key or bad
value of config.
)doc";

}  // namespace

namespace {

/// OccupancyMap.integrate(): one scan's points from its origin.
py::dict integrate(OccupancyMap& map, const py::handle& points, const py::handle& origin, bool discretize) {
  grid::IntegrateOptions options;
  options.discretize = discretize;
  const Rows<Eigen::Vector3f> p = pointsFloat(points, "points");
  const Eigen::Vector3f o = vector3(origin, "origin").cast<float>();
  // As the command line: a cloud with no point to integrate is a mistake, not a scan.
  if (std::none_of(p.rows.begin(), p.rows.end(), [](const Eigen::Vector3f& q) { return q.allFinite(); })) {
    throw InvalidArgument(p.rows.empty() ? "points: the cloud is empty (0 points)"
                                         : "points: none of the " + std::to_string(p.rows.size()) +
                                               " points is finite");
  }
  grid::ScanStats stats;
  {
    py::gil_scoped_release unlocked;
    stats = map.integrate(p.rows, o, options);
  }
  return scanResult(map, stats);
}

/// OccupancyMap.integrate_depth(): one depth frame from its pose.
py::dict integrateDepth(OccupancyMap& map, const py::handle& depth, const py::handle& T_world_camera,
                        const sensor::DepthCamera* camera, double scale, const std::string& no_return,
                        bool discretize) {
  const py::array image = py::array::ensure(depth);
  if (!image || image.ndim() != 2) throw InvalidArgument("depth: give an (H, W) array");
  const char kind = image.dtype().kind();
  const auto height = static_cast<int>(image.shape(0)), width = static_cast<int>(image.shape(1));
  // The default camera (None), or the DepthCamera's.
  const sensor::PinholeCamera intrinsics = camera ? camera->config().camera : sensor::PinholeCamera{};
  grid::DepthOptions options;
  options.scale = scale;
  options.no_return = grid::noReturnFromName(no_return);
  grid::IntegrateOptions integrate_options;
  integrate_options.discretize = discretize;
  const Eigen::Isometry3d T = pose(T_world_camera, "T_world_camera");
  grid::ScanStats stats;
  if (kind == 'u' && image.itemsize() == 2) {
    const auto raw = py::array_t<std::uint16_t, py::array::c_style | py::array::forcecast>::ensure(image);
    const grid::DepthImage view{width, height, {raw.data(), static_cast<std::size_t>(raw.size())}, {}};
    py::gil_scoped_release unlocked;
    stats = map.integrateDepth(view, intrinsics, T, options, integrate_options);
  } else if (kind == 'f') {
    const auto metres = py::array_t<float, py::array::c_style | py::array::forcecast>::ensure(image);
    const grid::DepthImage view{width, height, {}, {metres.data(), static_cast<std::size_t>(metres.size())}};
    py::gil_scoped_release unlocked;
    stats = map.integrateDepth(view, intrinsics, T, options, integrate_options);
  } else {
    throw InvalidArgument("depth: dtype " + std::string(py::str(image.dtype())) +
                          " is neither uint16 (raw values) nor floating (metres)");
  }
  return scanResult(map, stats);
}

void bindMapScans(py::class_<OccupancyMap>& cls) {
  cls.def(py::init([](double resolution, const std::map<std::string, double>& config) {
             return OccupancyMap(mapConfig(resolution, config));
           }),
           occupancyMapDoc().c_str())
      .def("integrate", &integrate, kIntegrateDoc)
      .def("integrate_depth", &integrateDepth, kIntegrateDepthDoc)
      .def(
          "save",
          [](const OccupancyMap& map, const std::filesystem::path& path) {
            py::gil_scoped_release unlocked;
            grid::saveMap(map, path);
          },
          kSaveDoc);
}

void bindMapQueries(py::class_<OccupancyMap>& cls) {
  cls.def_property_readonly("resolution", [](const OccupancyMap& map) { return map.config().resolution; },
                             "Voxel edge [m].")
      .def_property_readonly("config", [](const OccupancyMap& map) { return configDict(map.config()); },
                             "The sensor model and map parameters as a dict.")
      .def(
          "counts",
          [](const OccupancyMap& map) {
            py::dict d;
            const std::size_t measured = map.measuredCount(), occupied = map.occupiedCount(), free = map.freeCount();
            d["measured"] = measured;
            d["occupied"] = occupied;
            d["free"] = free;
            d["unknown"] = measured - occupied - free;
            d["octomap_occupied"] = map.octomapOccupiedCount();
            d["marked"] = map.markedCount();
            return d;
          },
          kCountsDoc)
      .def(
          "bounds",
          [](const OccupancyMap& map) -> py::object {
            const auto box = map.measuredBoundsWorld();
            if (!box) return py::none();
            std::vector<double> lo(box->min().data(), box->min().data() + 3), hi(box->max().data(),
                                   box->max().data() + 3);
            return py::make_tuple(ownedArray(std::move(lo), {3}), ownedArray(std::move(hi), {3}));
          },
          kBoundsDoc)
      .def(
          "probability",
          [](const OccupancyMap& map, const py::handle& points) {
            return perPoint(map, points, [&](const grid::Index3& ijk) { return map.probability(ijk); });
          },
          kProbabilityDoc)
      .def(
          "log_odds",
          [](const OccupancyMap& map, const py::handle& points) {
            return perPoint(map, points,
                            [&](const grid::Index3& ijk) { return static_cast<double>(map.logOdds(ijk)); });
          },
          kLogOddsDoc)
      .def(
          "measured_voxels",
          [](const OccupancyMap& map) {
            const auto voxels = map.measuredVoxels();
            std::vector<Eigen::Vector3d> centres(voxels.size());
            std::vector<float> log_odds(voxels.size());
            for (std::size_t i = 0; i < voxels.size(); ++i) {
              centres[i] = map.indexToWorld(voxels[i].ijk);
              log_odds[i] = voxels[i].log_odds;
            }
            return py::make_tuple(ownedRows(std::move(centres)),
                                  ownedArray(std::move(log_odds), {static_cast<py::ssize_t>(voxels.size())}));
          },
          kMeasuredVoxelsDoc)
      .def(
          "proximity_marks",
          [](const OccupancyMap& map) {
            const auto marks = map.proximityMarks();
            std::vector<Eigen::Vector3d> centres(marks.size());
            std::vector<std::int32_t> distances(marks.size());
            for (std::size_t i = 0; i < marks.size(); ++i) {
              centres[i] = map.indexToWorld(marks[i].ijk);
              distances[i] = marks[i].distance;
            }
            return py::make_tuple(ownedRows(std::move(centres)),
                                  ownedArray(std::move(distances), {static_cast<py::ssize_t>(marks.size())}));
          },
          kProximityMarksDoc)
      .def("__repr__", [](const OccupancyMap& map) {
        return "<nbv.OccupancyMap resolution=" + nbv::numberText(map.config().resolution) + " m, " +
               std::to_string(map.measuredCount()) + " measured voxels>";
      });
}

void bindOccupancyMap(py::module_& m) {
  py::class_<OccupancyMap> cls(m, "OccupancyMap", kOccupancyMapClassDoc);
  bindMapScans(cls);
  bindMapQueries(cls);
}

void bindLoadMap(py::module_& m) {

  m.def(
      "load_map",
      [](const std::filesystem::path& path, std::size_t max_map_mb, const std::map<std::string, double>& config) {
        grid::MapLoadOptions options;
        options.config = mapConfig(options.config.resolution, config);
        options.max_bytes = max_map_mb << 20;
        grid::MapLoadReport report;
        std::optional<OccupancyMap> map;
        {
          py::gil_scoped_release unlocked;
          map.emplace(grid::loadMap(path, options, &report));
        }
        if (!report.dropped.empty()) {
          const std::string warning = path.string() + " (an OctoMap " + report.tree_type + ") holds " + report.dropped +
                                      ", which a map does not keep";
          if (PyErr_WarnEx(PyExc_UserWarning, warning.c_str(), 2) != 0) throw py::error_already_set();
        }
        return std::move(*map);
      },
      kLoadMapDoc);
}

}  // namespace

void bindMap(py::module_& m) {
  bindOccupancyMap(m);
  bindLoadMap(m);
  m.attr("_MAX_MAP_MB") = grid::MapLoadOptions{}.max_bytes >> 20;  // load_map()'s default cap
  // The map configuration's fields and their defaults (grid::NBV_MAP_CONFIG_FIELDS), in order:
  // the keywords the Python layer takes.
  py::dict defaults;
  for (const grid::MapConfigField& f : grid::mapConfigFields()) defaults[f.name] = f.default_value;
  m.attr("_MAP_CONFIG_DEFAULTS") = defaults;
}

}  // namespace nbv::python
