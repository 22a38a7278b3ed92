#include "export_ply.hpp"

#include "app_support.hpp"
#include "output_file.hpp"

#include "nbv/errors.hpp"
#include "nbv/grid/map_io.hpp"
#include "nbv/kernels/information_gain.hpp"
#include "nbv/sensor/pinhole_camera.hpp"

#include <CLI/CLI.hpp>

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <fstream>
#include <limits>
#include <memory>
#include <optional>
#include <set>
#include <sstream>
#include <string>
#include <tuple>
#include <vector>

namespace nbv::apps {

namespace {

namespace fs = std::filesystem;
using grid::Index3;
using Rgb = std::array<std::uint8_t, 3>;

struct ExportCommand {
  std::string map;
  std::string ply;
  std::string what = "occupied";
  std::string color = "class";
  bool cubes = false;
  std::string views;
  std::string ig;
  std::string metric;
};

// The class colours (SEMANTICS.md "The map": occupied P > 0.8, free P < 0.2).
constexpr Rgb kOccupied{200, 40, 40};
constexpr Rgb kFree{60, 170, 80};
constexpr Rgb kUncertain{150, 150, 150};  // measured, 0.2 <= P <= 0.8
constexpr Rgb kMarked{70, 110, 220};      // unmeasured with a proximity mark
constexpr Rgb kFrontier{240, 180, 30};    // unknown next to space seen empty

/// A voxel to draw: its index, the class colour and the value the other colourings use.
struct Voxel {
  Index3 ijk;
  Rgb class_color;
  double probability;            ///< P_o; 0.5 when unmeasured
  std::optional<std::int32_t> mark;  ///< proximity distance [voxel steps], unmeasured only
};

/// Unmeasured voxels with a face next to a measured voxel seen more empty than not (P < 0.5),
/// in z, y, x order.
std::vector<Index3> unknownFrontier(const grid::OccupancyMap& map) {
  std::set<std::tuple<int, int, int>> frontier;
  for (const grid::MeasuredVoxel& v : map.measuredVoxels()) {
    if (grid::OccupancyMap::probabilityOf(v.log_odds) >= 0.5) continue;
    for (int a = 0; a < 3; ++a) {
      for (int s : {-1, 1}) {
        Index3 n = v.ijk;
        n[a] += s;
        if (!map.isMeasured(n)) frontier.insert({n.z(), n.y(), n.x()});
      }
    }
  }
  std::vector<Index3> out;
  for (const auto& [z, y, x] : frontier) out.emplace_back(x, y, z);
  return out;
}

std::vector<Voxel> selectVoxels(const grid::OccupancyMap& map, const std::string& what) {
  std::vector<Voxel> out;
  const bool all = what == "all";
  if (all || what == "occupied" || what == "free") {
    for (const grid::MeasuredVoxel& v : map.measuredVoxels()) {
      const double p = grid::OccupancyMap::probabilityOf(v.log_odds);
      const Rgb color = p > 0.8 ? kOccupied : (p < 0.2 ? kFree : kUncertain);
      if (all || (what == "occupied" && p > 0.8) || (what == "free" && p < 0.2)) out.push_back({v.ijk, color, p, {}});
    }
  }
  if (all || what == "marked") {
    for (const grid::ProximityMark& m : map.proximityMarks()) out.push_back({m.ijk, kMarked, 0.5, m.distance});
  }
  if (what == "unknown-frontier") {
    for (const Index3& ijk : unknownFrontier(map)) out.push_back({ijk, kFrontier, 0.5, map.proximity(ijk)});
  }
  return out;
}

Rgb colorOf(const Voxel& v, const std::string& coloring, double proximity_max) {
  if (coloring == "class") return v.class_color;
  if (coloring == "probability") return viridis(v.probability);
  if (coloring == "entropy") return viridis(kernels::entropyNats(v.probability) / std::log(2.0));
  // proximity: near the surface bright, far dark; voxels without a mark grey
  if (!v.mark) return kUncertain;
  return viridis(1.0 - static_cast<double>(*v.mark) / proximity_max);
}

struct Ply {
  std::vector<Eigen::Vector3f> vertices;
  std::vector<Rgb> colors;
  std::vector<std::array<std::int32_t, 3>> faces;

  std::int32_t add(const Eigen::Vector3f& p, const Rgb& c) {
    vertices.push_back(p);
    colors.push_back(c);
    return static_cast<std::int32_t>(vertices.size() - 1);
  }
};

/// A voxel as a cube: its 8 corners and 12 outward triangles.
void addCube(Ply& ply, const Eigen::Vector3f& centre, float half, const Rgb& c) {
  const std::int32_t first = static_cast<std::int32_t>(ply.vertices.size());
  for (int k = 0; k < 8; ++k) {  // corner k: bit 0 x, bit 1 y, bit 2 z
    ply.add(centre + half * Eigen::Vector3f((k & 1) ? 1.0f : -1.0f, (k & 2) ? 1.0f : -1.0f, (k & 4) ? 1.0f : -1.0f), c);
  }
  static constexpr std::int32_t kQuads[6][4] = {{0, 2, 3, 1}, {4, 5, 7, 6}, {0, 1, 5, 4}, {2, 6, 7, 3}, {0, 4, 6, 2}, {1, 3, 7, 5}};
  for (const auto& q : kQuads) {
    ply.faces.push_back({first + q[0], first + q[1], first + q[2]});
    ply.faces.push_back({first + q[0], first + q[2], first + q[3]});
  }
}

/// A camera frustum: the optical centre and the 4 image corners at `depth` [m], as 4 side
/// triangles, in the camera model of SEMANTICS.md "Views and rays".
void addFrustum(Ply& ply, const Eigen::Isometry3d& T_world_camera, double depth, const Rgb& c) {
  const sensor::PinholeCamera camera;
  const double hx = camera.cx / camera.fx * depth, hy = camera.cy / camera.fy * depth;
  const std::int32_t apex = ply.add(T_world_camera.translation().cast<float>(), c);
  std::int32_t corner[4];
  const double sx[4] = {-1, 1, 1, -1}, sy[4] = {-1, -1, 1, 1};
  for (int k = 0; k < 4; ++k) corner[k] = ply.add((T_world_camera * Eigen::Vector3d(sx[k] * hx, sy[k] * hy, depth)).cast<float>(), c);
  for (int k = 0; k < 4; ++k) ply.faces.push_back({apex, corner[k], corner[(k + 1) % 4]});
}

void writePly(const fs::path& path, const Ply& ply, const std::string& comment) {
  std::ofstream out(path, std::ios::binary);
  if (!out) throw FileError(path, "cannot write");
  out << "ply\nformat binary_little_endian 1.0\ncomment " << comment << "\nelement vertex " << ply.vertices.size()
      << "\nproperty float x\nproperty float y\nproperty float z\nproperty uchar red\nproperty uchar green\n"
         "property uchar blue\n";
  if (!ply.faces.empty()) out << "element face " << ply.faces.size() << "\nproperty list uchar int vertex_indices\n";
  out << "end_header\n";
  for (std::size_t i = 0; i < ply.vertices.size(); ++i) {
    out.write(reinterpret_cast<const char*>(ply.vertices[i].data()), 3 * sizeof(float));
    out.write(reinterpret_cast<const char*>(ply.colors[i].data()), 3);
  }
  for (const auto& f : ply.faces) {
    const std::uint8_t three = 3;
    out.write(reinterpret_cast<const char*>(&three), 1);
    out.write(reinterpret_cast<const char*>(f.data()), 3 * sizeof(std::int32_t));
  }
  if (!out.flush()) throw FileError(path, "write failed");
}

/// Column `metric` of an `nbv evaluate --csv` file, one value per view in view order.
std::vector<double> readIgColumn(const fs::path& path, const std::string& metric, std::size_t views) {
  std::ifstream in(path);
  if (!in) throw FileError(path, "cannot read");
  std::string line;
  if (!std::getline(in, line)) throw FileError(path, "empty: expected a header 'view,<metric>,...'");
  const std::vector<std::string> header = splitList(line);
  const auto column = std::find(header.begin(), header.end(), metric);
  if (header.empty() || header[0] != "view" || column == header.end()) {
    throw FileError(path, "line 1: the header '" + line + "' has no column '" + metric + "' after 'view'");
  }
  const auto c = static_cast<std::size_t>(column - header.begin());
  std::vector<double> values(views, std::numeric_limits<double>::quiet_NaN());
  for (std::size_t number = 2; std::getline(in, line); ++number) {
    if (line.empty()) continue;
    std::vector<std::string> cells;
    std::stringstream cells_in(line);
    for (std::string cell; std::getline(cells_in, cell, ',');) cells.push_back(cell);
    std::size_t view = 0;
    double value = 0.0;
    try {
      std::size_t used = 0;
      view = std::stoul(cells.at(0), &used);
      if (used != cells[0].size()) throw std::invalid_argument("view");
      value = std::stod(cells.at(c), &used);
      if (used != cells[c].size() || !std::isfinite(value)) throw std::invalid_argument("value");
    } catch (const std::exception&) {
      throw FileError(path, "line " + std::to_string(number) + ": '" + line + "' is not a view index and finite values");
    }
    if (view >= views) {
      throw FileError(path, "line " + std::to_string(number) + ": view " + std::to_string(view) + " is outside the " +
                                std::to_string(views) + " views");
    }
    values[view] = value;
  }
  for (std::size_t v = 0; v < views; ++v) {
    if (std::isnan(values[v])) throw FileError(path, "no value for view " + std::to_string(v));
  }
  return values;
}

void runExport(const ExportCommand& c) {
  if (c.views.empty() != c.ig.empty() || c.ig.empty() != c.metric.empty()) {
    throw InvalidArgument("the candidate frusta need --views, --ig and --metric together");
  }
  checkWritable(c.ply);
  const grid::OccupancyMap map = readMap(c.map);
  const std::vector<Voxel> voxels = selectVoxels(map, c.what);
  const double proximity_max = std::max(1.0, 2.0 * map.config().proximity_range / map.lattice().resolution());
  Ply ply;
  const auto half = static_cast<float>(0.5 * map.lattice().resolution());
  for (const Voxel& v : voxels) {
    const Eigen::Vector3f centre = map.indexToWorld(v.ijk).cast<float>();
    const Rgb color = colorOf(v, c.color, proximity_max);
    if (c.cubes) {
      addCube(ply, centre, half, color);
    } else {
      ply.add(centre, color);
    }
  }
  std::size_t frusta = 0;
  if (!c.views.empty()) {
    const std::vector<planner::View> views = viewspace(c.views);
    const std::vector<double> ig = readIgColumn(c.ig, c.metric, views.size());
    const auto [lo, hi] = std::minmax_element(ig.begin(), ig.end());
    for (std::size_t v = 0; v < views.size(); ++v) {
      const double t = *hi > *lo ? (ig[v] - *lo) / (*hi - *lo) : 1.0;
      addFrustum(ply, views[v].T_world_camera, 0.08, viridis(t));
    }
    frusta = views.size();
  }
  const std::string comment = "nbv export of " + fs::path(c.map).filename().string() + ": " + c.what + " voxels coloured by " +
                              c.color + (c.cubes ? " as cubes" : " at their centres") +
                              (frusta > 0 ? ", candidate frusta coloured by " + c.metric : "");
  writeAtomically(c.ply, [&](const fs::path& temporary) { writePly(temporary, ply, comment); });
  std::printf("%zu voxels (%s, coloured by %s)%s -> %s: %zu vertices, %zu faces\n", voxels.size(), c.what.c_str(),
              c.color.c_str(), frusta > 0 ? (", " + std::to_string(frusta) + " frusta").c_str() : "", c.ply.c_str(),
              ply.vertices.size(), ply.faces.size());
  if (c.what == "occupied" && voxels.empty() && map.measuredCount() > 0) {
    // One hit gives L = logit(0.7) < logit(0.8): a surface seen once is not occupied yet.
    std::fprintf(stderr, "nbv: note: none of the map's %zu measured voxels is occupied (P > 0.8): one hit leaves "
                         "P = 0.7 (%zu voxels are at P >= 0.5), so a surface needs hits from two scans; "
                         "`--what all --color probability` draws every measured voxel by its probability\n",
                 map.measuredCount(), map.octomapOccupiedCount());
  }
}

}  // namespace

std::vector<VoxelClass> voxelClasses(const grid::OccupancyMap& map) {
  std::vector<VoxelClass> classes = {{"occupied", "P > 0.8", kOccupied, {}},
                                     {"uncertain", "measured, 0.2 <= P <= 0.8", kUncertain, {}},
                                     {"free", "P < 0.2", kFree, {}},
                                     {"marked", "unmeasured, with a proximity mark", kMarked, {}},
                                     {"frontier", "unmeasured, next to a voxel seen empty", kFrontier, {}}};
  const auto centre = [&](const Index3& ijk) -> Eigen::Vector3f { return map.indexToWorld(ijk).cast<float>(); };
  for (const grid::MeasuredVoxel& v : map.measuredVoxels()) {
    const double p = grid::OccupancyMap::probabilityOf(v.log_odds);
    classes[p > 0.8 ? 0 : (p < 0.2 ? 2 : 1)].centres.push_back(centre(v.ijk));
  }
  for (const grid::ProximityMark& m : map.proximityMarks()) classes[3].centres.push_back(centre(m.ijk));
  for (const Index3& ijk : unknownFrontier(map)) classes[4].centres.push_back(centre(ijk));
  return classes;
}

std::array<std::uint8_t, 3> viridis(double t) {
  // Matplotlib's viridis at 0, 0.25, 0.5, 0.75, 1, linearly between.
  static constexpr double kStops[5][3] = {{68, 1, 84}, {59, 82, 139}, {33, 145, 140}, {94, 201, 98}, {253, 231, 37}};
  t = std::isfinite(t) ? std::clamp(t, 0.0, 1.0) : 0.0;
  const double x = t * 4.0;
  const int k = std::min(3, static_cast<int>(x));
  const double f = x - k;
  std::array<std::uint8_t, 3> rgb{};
  for (int i = 0; i < 3; ++i) rgb[i] = static_cast<std::uint8_t>(std::lround(kStops[k][i] + f * (kStops[k + 1][i] - kStops[k][i])));
  return rgb;
}

void addExportCommand(CLI::App& app) {
  auto c = std::make_shared<ExportCommand>();
  CLI::App* e = app.add_subcommand(
      "export", "Write a map's voxels as a coloured binary PLY (MeshLab, CloudCompare, Open3D), optionally with the "
                "candidate views as frusta coloured by their information gain.");
  e->add_option("--map", c->map, "The map (.vdb, .ot, .bt)")->required();
  e->add_option("--ply", c->ply, "Output PLY (binary, x y z red green blue per vertex; faces for cubes and frusta; -: standard output)")->required();
  e->add_option("--what", c->what,
                "occupied (P > 0.8), free (P < 0.2), marked (unmeasured with a proximity mark), unknown-frontier "
                "(unmeasured voxels next to a voxel seen empty, P < 0.5), or all (every measured and marked voxel)")
      ->check(CLI::IsMember({"occupied", "free", "marked", "unknown-frontier", "all"}))
      ->capture_default_str();
  e->add_option("--color", c->color,
                "class (occupied red, free green, uncertain grey, marked blue, frontier amber), probability, entropy "
                "(viridis, 0 to 1 bit), or proximity (viridis, bright near the surface)")
      ->check(CLI::IsMember({"class", "probability", "entropy", "proximity"}))
      ->capture_default_str();
  e->add_flag("--cubes", c->cubes, "Each voxel as a cube (8 vertices, 12 triangles) instead of a point at its centre");
  e->add_option("--views", c->views, "Candidate views to draw as frusta: dome48 or a view file (with --ig and --metric)");
  e->add_option("--ig", c->ig, "The views' information gain: a CSV of nbv evaluate --csv");
  e->add_option("--metric", c->metric, "The --ig column that colours the frusta (viridis: lowest dark, highest yellow)");
  e->callback([c] { runExport(*c); });
}

}  // namespace nbv::apps
