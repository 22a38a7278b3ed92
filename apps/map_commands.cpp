#include "map_commands.hpp"

#include "app_support.hpp"
#include "output_file.hpp"

#include "nbv/errors.hpp"
#include "nbv/grid/map_io.hpp"
#include "nbv/sensor/point_cloud_io.hpp"

#include <algorithm>
#include <CLI/CLI.hpp>

#include <cmath>
#include <filesystem>
#include <iostream>
#include <memory>
#include <optional>
#include <sstream>
#include <string>
#include <vector>

namespace nbv::apps {

namespace {

namespace fs = std::filesystem;
using grid::OccupancyMap;

const char* formatName(grid::MapFormat format) {
  switch (format) {
    case grid::MapFormat::Vdb: return "OpenVDB (.vdb)";
    case grid::MapFormat::OctomapOt: return "OctoMap full (.ot)";
    case grid::MapFormat::OctomapBt: return "OctoMap binary (.bt)";
  }
  return "?";
}

void saveMapAtomically(const OccupancyMap& map, const fs::path& path) {
  const grid::MapFormat format = grid::mapFormatFromPath(path);
  writeAtomically(path, [&](const fs::path& temporary) { grid::saveMap(map, temporary, format); });
}

struct IntegrateOptions {
  std::string map;
  std::string cloud;
  std::vector<double> origin;
  std::string viewspace;             // with view_index: the origin is that view's position
  std::optional<int> view_index;
  std::optional<double> resolution;  // only for a new map
  std::size_t max_voxels = 0;        // 0: no cap
};

/// The sensor origin: --origin, or the position of --view-index in --viewspace.
Eigen::Vector3f sensorOrigin(const IntegrateOptions& o) {
  if (!o.origin.empty()) return Eigen::Vector3d(o.origin[0], o.origin[1], o.origin[2]).cast<float>();
  const std::vector<planner::View> views = viewspace(o.viewspace.empty() ? "dome48" : o.viewspace);
  if (*o.view_index < 0 || static_cast<std::size_t>(*o.view_index) >= views.size()) {
    throw InvalidArgument("--view-index " + std::to_string(*o.view_index) + " is outside the viewspace's " +
                          std::to_string(views.size()) + " views");
  }
  return views[static_cast<std::size_t>(*o.view_index)].T_world_camera.translation().cast<float>();
}

void runIntegrate(const IntegrateOptions& o) {
  const fs::path map_path(o.map);
  grid::mapFormatFromPath(map_path);  // refuse an unknown extension before any work
  checkWritable(map_path);
  if (o.origin.empty() == !o.view_index.has_value()) {
    throw InvalidArgument("give the sensor origin either as --origin X Y Z or as --view-index I (with --viewspace)");
  }
  if (!o.viewspace.empty() && !o.view_index) throw InvalidArgument("--viewspace needs --view-index");
  const Eigen::Vector3f origin = sensorOrigin(o);
  std::unique_ptr<OccupancyMap> map;
  if (fs::exists(map_path)) {
    map = std::make_unique<OccupancyMap>(grid::loadMap(map_path));
    if (o.resolution && *o.resolution != map->config().resolution) {
      throw nbv::InvalidArgument(o.map + ": map has resolution " +
                                  std::to_string(map->config().resolution) +
                                  " m, --resolution asks for " + std::to_string(*o.resolution));
    }
  } else {
    OccupancyMap::Config config;
    if (o.resolution) config.resolution = *o.resolution;
    map = std::make_unique<OccupancyMap>(config);
  }
  const std::vector<Eigen::Vector3f> points = sensor::readPlyCloud(o.cloud);
  if (points.empty()) throw nbv::CloudFileError(o.cloud, "cloud has no points");
  // Non-finite points are skipped (SEMANTICS.md "The map"); a cloud of nothing else is almost surely a mistake.
  if (std::none_of(points.begin(), points.end(), [](const Eigen::Vector3f& p) { return p.allFinite(); })) {
    throw nbv::CloudFileError(o.cloud, "cloud has no finite point (all " + std::to_string(points.size()) +
                                              " are NaN or Inf)");
  }
  grid::IntegrateOptions integrate_options;
  integrate_options.max_measured_voxels = o.max_voxels;
  const grid::ScanStats stats = map->integrate(points, origin, integrate_options);
  saveMapAtomically(*map, map_path);
  std::cout << "integrated " << stats.points << " points (" << stats.hits << " hits, "
            << stats.beyond_range << " beyond max range, " << stats.skipped_points
            << " skipped): " << stats.voxels_hit << " voxels hit, " << stats.voxels_missed
            << " missed, " << stats.voxels_marked << " proximity marks set\n"
            << o.map << ": " << map->measuredCount() << " measured voxels\n";
}

void runConvert(const std::string& in, const std::string& out) {
  const grid::MapFormat out_format = grid::mapFormatFromPath(out);
  checkWritable(out);
  const OccupancyMap map = grid::loadMap(in);
  saveMapAtomically(map, out);
  std::cout << in << " -> " << out << " (" << formatName(out_format) << "): "
            << map.measuredCount() << " measured voxels\n";
}

void runInfo(const std::string& path) {
  const grid::MapFormat format = grid::mapFormatFromPath(path);
  const OccupancyMap map = grid::loadMap(path, format);
  const OccupancyMap::Config& c = map.config();
  const std::size_t measured = map.measuredCount();
  const std::size_t occupied = map.occupiedCount();
  const std::size_t free = map.freeCount();
  std::ostringstream out;
  // Two rules name a voxel occupied: the metrics' class (P > 0.8, reached after two hits) and
  // OctoMap's isNodeOccupied() (L > 0, P > 0.5, one hit); a one-scan map differs in them.
  out << "map:         " << path << '\n'
      << "format:      " << formatName(format) << '\n'
      << "resolution:  " << c.resolution << " m\n"
      << "measured:    " << measured << " voxels\n"
      << "  occupied:  " << occupied << " (class occupied of the metrics: P > " << c.occupied_threshold << ")\n"
      << "  free:      " << free << " (P < " << c.free_threshold << ")\n"
      << "  unknown:   " << measured - occupied - free << " (" << c.free_threshold << " <= P <= "
      << c.occupied_threshold << ")\n"
      << "  occupied for OctoMap: " << map.octomapOccupiedCount() << " (isNodeOccupied: L > 0, P > 0.5)\n"
      << "marked:      " << map.markedCount() << " proximity marks\n";
  if (const auto bounds = map.measuredBoundsWorld()) {
    out << "bounds:      [" << bounds->min().transpose() << "] .. [" << bounds->max().transpose()
        << "] m\n";
  } else {
    out << "bounds:      (no measured voxel)\n";
  }
  out << "memory:      " << map.memoryBytes() << " bytes\n"
      << "sensor:      p_hit " << c.p_hit << ", p_miss " << c.p_miss << ", clamps [" << c.clamp_min
      << ", " << c.clamp_max << "], max range " << c.max_range << " m, proximity range "
      << c.proximity_range << " m\n";
  std::cout << out.str();
}

}  // namespace

void addMapCommands(CLI::App& app) {
  auto integrate_options = std::make_shared<IntegrateOptions>();
  CLI::App* integrate = app.add_subcommand(
      "integrate", "Integrate a point cloud into a map (created if absent, else updated).");
  integrate->add_option("--map", integrate_options->map, "Map file (.vdb, .ot or .bt)")->required();
  integrate->add_option("--cloud", integrate_options->cloud,
                        "PLY cloud (ascii or binary, x y z in the world frame)")
      ->required();
  integrate->add_option("--origin", integrate_options->origin, "Sensor origin X Y Z [m], world frame")
      ->expected(3)
      ->check(finiteNumber());
  integrate->add_option("--viewspace", integrate_options->viewspace,
                        "With --view-index: dome48 (default) or a view file, instead of --origin");
  integrate->add_option("--view-index", integrate_options->view_index,
                        "Take the sensor origin from this view of --viewspace (as `nbv render` used it)");
  integrate->add_option("--resolution", integrate_options->resolution,
                        "Voxel size [m] of a new map (default 0.01)")
      ->check(positiveNumber());
  integrate->add_option("--max-voxels", integrate_options->max_voxels,
                        "Refuse a scan that would leave the map more measured voxels than this (0: no cap)")
      ->capture_default_str();
  integrate->callback([integrate_options] { runIntegrate(*integrate_options); });

  auto convert_in = std::make_shared<std::string>();
  auto convert_out = std::make_shared<std::string>();
  CLI::App* convert = app.add_subcommand(
      "convert", "Convert a map between .vdb, .ot and .bt (by extension).");
  convert->add_option("IN", *convert_in, "Input map")->required();
  convert->add_option("OUT", *convert_out, "Output map")->required();
  convert->callback([convert_in, convert_out] { runConvert(*convert_in, *convert_out); });

  auto info_path = std::make_shared<std::string>();
  CLI::App* info = app.add_subcommand("info", "Print a map's resolution, voxel counts, bounds, memory.");
  info->add_option("MAP", *info_path, "Map file (.vdb, .ot or .bt)")->required();
  info->callback([info_path] { runInfo(*info_path); });
}

}  // namespace nbv::apps
