#include "map_commands.hpp"

#include "app_support.hpp"
#include "output_file.hpp"

#include "nbv/errors.hpp"
#include "nbv/grid/map_io.hpp"
#include "nbv/sensor/depth_io.hpp"
#include "nbv/sensor/point_cloud_io.hpp"

#include <algorithm>
#include <CLI/CLI.hpp>

#include <chrono>
#include <cmath>
#include <filesystem>
#include <iostream>
#include <map>
#include <memory>
#include <optional>
#include <sstream>
#include <string>
#include <utility>
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
  std::string cloud;                 // one of cloud, depth, tum
  std::string depth;
  std::string tum;
  std::string frames;                // with poses: a numbered image folder and its pose file
  std::string poses;
  std::vector<double> origin;        // a cloud's sensor origin, or
  std::vector<double> pose;          // a depth image's T_world_camera: TX TY TZ QX QY QZ QW, or
  std::string viewspace;             // with view_index: that view's pose
  std::optional<int> view_index;
  std::vector<double> camera;        // W H FX FY CX CY; empty: the default camera
  double depth_scale = 5000.0;
  std::string no_return = "drop";
  /// The map configuration's fields given by flag (grid::NBV_MAP_CONFIG_FIELDS), by name: a
  /// new map's; an existing .vdb keeps its own, an OctoMap file its resolution.
  std::map<std::string, double> map_config;
  std::size_t max_voxels = 0;        // 0: no cap
  bool discretize = false;           // OctoMap's discretize: one ray per distinct end voxel
};

/// The pose of --view-index in --viewspace.
Eigen::Isometry3d viewPose(const IntegrateOptions& o) {
  const std::vector<planner::View> views = viewspace(o.viewspace.empty() ? "dome48" : o.viewspace);
  if (*o.view_index < 0 || static_cast<std::size_t>(*o.view_index) >= views.size()) {
    throw InvalidArgument("--view-index " + std::to_string(*o.view_index) + " is outside the viewspace's " +
                          std::to_string(views.size()) + " views");
  }
  return views[static_cast<std::size_t>(*o.view_index)].T_world_camera;
}

/// --pose TX TY TZ QX QY QZ QW as T_world_camera (the quaternion normalised).
Eigen::Isometry3d poseOf(const std::vector<double>& p) {
  const Eigen::Quaterniond q(p[6], p[3], p[4], p[5]);
  if (!(q.norm() > 1e-9)) throw InvalidArgument("--pose: the quaternion QX QY QZ QW is zero");
  Eigen::Isometry3d T = Eigen::Isometry3d::Identity();
  T.linear() = q.normalized().toRotationMatrix();
  T.translation() = Eigen::Vector3d(p[0], p[1], p[2]);
  return T;
}

sensor::PinholeCamera cameraOf(const std::vector<double>& c) {
  sensor::PinholeCamera camera;
  if (!c.empty()) {
    if (c[0] != std::floor(c[0]) || c[1] != std::floor(c[1])) throw InvalidArgument("--camera: W and H must be whole pixels");
    camera = {static_cast<int>(c[0]), static_cast<int>(c[1]), c[2], c[3], c[4], c[5]};
  }
  try {
    camera.validate();
  } catch (const InvalidArgument& e) {
    throw InvalidArgument(std::string("--camera: ") + e.what());
  }
  return camera;
}

/// A 16-bit depth PNG as an image of the camera's size. \throws naming the file.
grid::ScanStats integrateDepthFile(OccupancyMap& map, const fs::path& path, const sensor::PinholeCamera& camera,
                                   const Eigen::Isometry3d& T_world_camera, const grid::DepthOptions& depth_options,
                                   const grid::IntegrateOptions& options) {
  const sensor::DepthPng png = sensor::readDepthPng16(path);
  if (png.width != camera.width || png.height != camera.height) {
    throw FileError(path, "is " + std::to_string(png.width) + " x " + std::to_string(png.height) + " pixels; the camera is " +
                              std::to_string(camera.width) + " x " + std::to_string(camera.height) + " (--camera)");
  }
  return map.integrateDepth(grid::DepthImage{png.width, png.height, png.values, {}}, camera, T_world_camera, depth_options,
                            options);
}

/// The map --map names, loaded, or new with the given configuration. A .vdb map keeps the
/// configuration it was built with (sensor model, ranges, classes): another value is refused;
/// an OctoMap file stores only its resolution, so it is read with the other values given (or
/// the defaults) for this integration.
std::unique_ptr<OccupancyMap> openMap(const IntegrateOptions& o) {
  const fs::path path(o.map);
  const bool exists = fs::exists(path);
  const bool keeps_config = exists && grid::mapFormatFromPath(path) == grid::MapFormat::Vdb;
  OccupancyMap::Config config;
  if (!keeps_config) {
    for (const auto& [name, value] : o.map_config) config.*grid::mapConfigField(name)->member = value;
    try {
      config.validate();
    } catch (const InvalidArgument& e) {
      std::string flags;
      for (const auto& given : o.map_config) flags += (flags.empty() ? "" : " / ") + flagOf(given.first);
      throw InvalidArgument((flags.empty() ? std::string() : flags + ": ") + e.what());
    }
  }
  if (!exists) return std::make_unique<OccupancyMap>(config);
  auto map = std::make_unique<OccupancyMap>(readMap(o.map, config));
  const OccupancyMap::Config& held = map->config();
  for (const auto& [name, asked] : o.map_config) {
    const grid::MapConfigField& field = *grid::mapConfigField(name);
    const double stored = held.*field.member;
    if ((keeps_config || name == "resolution") && asked != stored) {
      const std::string unit = *field.unit ? std::string(" ") + field.unit : "";
      throw InvalidArgument(o.map + ": map has " + name + " " + nbv::numberText(stored) + unit + ", " + flagOf(name) +
                            " asks for " + nbv::numberText(asked) +
                            " (a map keeps the value it was built with; integrate into a new map)");
    }
  }
  if (!keeps_config) {
    std::cerr << "nbv: note: " << o.map << " (an OctoMap file) stores no range: this integration uses "
              << nbv::numberText(held.min_range) << " to " << nbv::numberText(held.max_range) << " m\n";
  }
  return map;
}

/// Integrates a sequence of depth frames one by one, with progress lines; their summed stats.
grid::ScanStats integrateFrames(OccupancyMap& map, const std::vector<sensor::TumFrame>& sequence, const sensor::PinholeCamera& camera,
                                const grid::DepthOptions& depth_options, const grid::IntegrateOptions& integrate_options) {
  grid::ScanStats stats;
  const auto start = std::chrono::steady_clock::now();
  for (std::size_t i = 0; i < sequence.size(); ++i) {
    stats += integrateDepthFile(map, sequence[i].depth_file, camera, sequence[i].T_world_camera, depth_options, integrate_options);
    showProgress(i + 1, sequence.size(), std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count(),
                 "frames");
  }
  return stats;
}

void runIntegrate(const IntegrateOptions& o) {
  const fs::path map_path(o.map);
  grid::mapFormatFromPath(map_path);  // refuse an unknown extension before any work
  checkWritable(map_path);
  const int inputs = (o.cloud.empty() ? 0 : 1) + (o.depth.empty() ? 0 : 1) + (o.tum.empty() ? 0 : 1) + (o.frames.empty() ? 0 : 1);
  if (inputs != 1) {
    throw InvalidArgument("give one input: --cloud CLOUD.ply, --depth DEPTH.png, --tum FOLDER or --frames FOLDER --poses FILE");
  }
  if (o.frames.empty() != o.poses.empty()) throw InvalidArgument("--frames FOLDER and --poses FILE go together");
  if (!o.viewspace.empty() && !o.view_index) throw InvalidArgument("--viewspace needs --view-index");
  if (!o.cloud.empty() && o.origin.empty() == !o.view_index.has_value()) {
    throw InvalidArgument("give the sensor origin either as --origin X Y Z or as --view-index I (with --viewspace)");
  }
  if (!o.depth.empty() && o.pose.empty() == !o.view_index.has_value()) {
    throw InvalidArgument("give the camera pose either as --pose TX TY TZ QX QY QZ QW or as --view-index I");
  }
  if (!o.tum.empty() && (!o.pose.empty() || o.view_index || !o.origin.empty())) {
    throw InvalidArgument("--tum takes its poses from groundtruth.txt: no --pose, --origin or --view-index");
  }
  if (!o.frames.empty() && (!o.pose.empty() || o.view_index || !o.origin.empty())) {
    throw InvalidArgument("--frames takes its poses from --poses: no --pose, --origin or --view-index");
  }
  if (!o.cloud.empty() && !o.pose.empty()) throw InvalidArgument("--pose is for --depth; a cloud takes --origin");
  const sensor::PinholeCamera camera = cameraOf(o.camera);
  grid::DepthOptions depth_options;
  depth_options.scale = o.depth_scale;
  depth_options.no_return = grid::noReturnFromName(o.no_return);
  const std::unique_ptr<OccupancyMap> map = openMap(o);
  grid::IntegrateOptions integrate_options;
  integrate_options.max_measured_voxels = o.max_voxels;
  integrate_options.discretize = o.discretize;
  grid::ScanStats stats;
  std::size_t frames = 1;
  if (!o.cloud.empty()) {
    const std::vector<Eigen::Vector3f> points = sensor::readPlyCloud(o.cloud);
    if (points.empty()) throw CloudFileError(o.cloud, "cloud has no points");
    // Non-finite points are skipped (SEMANTICS.md "The map"); a cloud of nothing else is almost surely a mistake.
    if (std::none_of(points.begin(), points.end(), [](const Eigen::Vector3f& p) { return p.allFinite(); })) {
      throw CloudFileError(o.cloud, "cloud has no finite point (all " + std::to_string(points.size()) + " are NaN or Inf)");
    }
    const Eigen::Vector3d origin_world =
        o.origin.empty() ? Eigen::Vector3d(viewPose(o).translation()) : Eigen::Vector3d(o.origin[0], o.origin[1], o.origin[2]);
    const Eigen::Vector3f origin = origin_world.cast<float>();
    stats = map->integrate(points, origin, integrate_options);
  } else if (!o.depth.empty()) {
    const Eigen::Isometry3d T = o.pose.empty() ? viewPose(o) : poseOf(o.pose);
    stats = integrateDepthFile(*map, o.depth, camera, T, depth_options, integrate_options);
  } else {  // a TUM RGB-D folder or a numbered one, frame by frame (SEMANTICS.md "Real sensor input")
    const std::vector<sensor::TumFrame> sequence =
        o.tum.empty() ? sensor::readFrameFolder(o.frames, o.poses) : sensor::readTumSequence(o.tum);
    frames = sequence.size();
    stats = integrateFrames(*map, sequence, camera, depth_options, integrate_options);
  }
  saveMapAtomically(*map, map_path);
  std::cout << "integrated " << frames << (frames == 1 ? " scan" : " scans") << ", " << stats.points << " points ("
            << stats.hits << " hits, " << stats.beyond_range << " beyond max range, "
            << (stats.too_near > 0 ? std::to_string(stats.too_near) + " nearer than min range, " : "") << stats.skipped_points
            << " skipped): " << stats.voxels_hit << " voxels hit, " << stats.voxels_missed << " missed, "
            << stats.voxels_marked << " proximity marks set\n"
            << o.map << ": " << map->measuredCount() << " measured voxels\n";
  if (const std::string warning = grid::beyondRangeWarning(stats, map->config()); !warning.empty()) {
    std::cerr << "nbv: warning: " << warning << " (--max-range)\n";
  }
}

void runConvert(const std::string& in, const std::string& out) {
  const grid::MapFormat out_format = grid::mapFormatFromPath(out);
  checkWritable(out);
  const OccupancyMap map = readMap(in);
  saveMapAtomically(map, out);
  std::cout << in << " -> " << out << " (" << formatName(out_format) << "): "
            << map.measuredCount() << " measured voxels\n";
  // OctoMap's files have no place for some of what the map holds: say what the copy lacks.
  std::string lost;
  if (out_format != grid::MapFormat::Vdb && map.markedCount() > 0) {
    lost = std::to_string(map.markedCount()) + " proximity marks (Proximity Count and Area Factor read them)";
  }
  if (out_format == grid::MapFormat::OctomapBt && map.measuredCount() > 0) {
    lost += (lost.empty() ? "" : " and ") + std::string("the probabilities (.bt keeps only occupied or free): its ") +
            std::to_string(map.octomapOccupiedCount()) +
            " voxels at L >= 0 (OctoMap's isNodeOccupied) as occupied, the others as free,";
  }
  if (!lost.empty()) {
    std::cerr << "nbv: note: " << out << " leaves out " << lost << " of " << in << "; a .vdb keeps everything\n";
  }
}

void runInfo(const std::string& path) {
  const grid::MapFormat format = grid::mapFormatFromPath(path);
  const OccupancyMap map = readMap(path);
  const OccupancyMap::Config& c = map.config();
  const std::size_t measured = map.measuredCount();
  const std::size_t occupied = map.occupiedCount();
  const std::size_t free = map.freeCount();
  std::ostringstream out;
  // Two rules name a voxel occupied: the metrics' class (P > 0.8, reached after two hits) and
  // OctoMap's isNodeOccupied() (L >= 0, P >= 0.5, one hit); a one-scan map differs in them.
  out << "map:         " << path << '\n'
      << "format:      " << formatName(format) << '\n'
      << "resolution:  " << c.resolution << " m\n"
      << "measured:    " << measured << " voxels\n"
      << "  occupied:  " << occupied << " (class occupied of the metrics: P > " << c.occupied_threshold << ")\n"
      << "  free:      " << free << " (P < " << c.free_threshold << ")\n"
      << "  unknown:   " << measured - occupied - free << " (" << c.free_threshold << " <= P <= "
      << c.occupied_threshold << ")\n"
      << "  occupied for OctoMap: " << map.octomapOccupiedCount() << " (isNodeOccupied: L >= 0, P >= 0.5)\n"
      << "marked:      " << map.markedCount() << " proximity marks\n";
  if (const auto bounds = map.measuredBoundsWorld()) {
    out << "bounds:      [" << bounds->min().transpose() << "] .. [" << bounds->max().transpose()
        << "] m\n";
  } else {
    out << "bounds:      (no measured voxel)\n";
  }
  out << "memory:      " << map.memoryBytes() << " bytes\n"
      << "config:     ";
  const char* separator = " ";
  for (const grid::MapConfigField& field : grid::mapConfigFields()) {
    out << std::exchange(separator, ", ") << field.name << " "
        << nbv::numberText(c.*field.member) << (*field.unit ? " " : "") << field.unit;
  }
  out << "\n";
  std::cout << out.str();
}

}  // namespace

void addMapCommands(CLI::App& app) {
  auto integrate_options = std::make_shared<IntegrateOptions>();
  CLI::App* integrate = app.add_subcommand(
      "integrate", "Integrate a point cloud, a depth image, a TUM RGB-D folder or a numbered frame folder into a map "
                   "(created if absent, else updated).");
  integrate->add_option("--map", integrate_options->map, "Map file (.vdb, .ot or .bt)")->required();
  integrate->add_option("--cloud", integrate_options->cloud, "PLY cloud (ascii or binary, x y z in the world frame)");
  integrate->add_option("--depth", integrate_options->depth,
                        "16-bit depth PNG (--depth-scale per metre, 0 = no return) taken from --pose or --view-index");
  integrate->add_option("--tum", integrate_options->tum,
                        "TUM RGB-D style folder: depth.txt, groundtruth.txt and their depth PNGs, frame by frame");
  integrate->add_option("--frames", integrate_options->frames,
                        "Folder of numbered 16-bit depth PNGs (frame order: the last number in each name), with --poses");
  integrate->add_option("--poses", integrate_options->poses,
                        "With --frames: one pose TX TY TZ QX QY QZ QW (T_world_camera) per line, one line per frame");
  integrate->add_option("--origin", integrate_options->origin, "A cloud's sensor origin X Y Z [m], world frame")
      ->expected(3)
      ->check(finiteNumber());
  integrate->add_option("--pose", integrate_options->pose,
                        "A depth image's camera pose TX TY TZ QX QY QZ QW (T_world_camera, optical frame z forward)")
      ->expected(7)
      ->check(finiteNumber());
  integrate->add_option("--viewspace", integrate_options->viewspace,
                        "With --view-index: dome48 (default) or a view file, instead of --origin or --pose");
  integrate->add_option("--view-index", integrate_options->view_index,
                        "Take the origin or pose from this view of --viewspace (as `nbv render` used it)");
  integrate->add_option("--camera", integrate_options->camera,
                        "Depth camera intrinsics W H FX FY CX CY [pixels] (default: 752 480 448.1008985853343 "
                        "448.1008985853343 376.5 240.5; a negative FX or FY flips that image axis)")
      ->expected(6)
      ->check(finiteNumber());
  integrate->add_option("--depth-scale", integrate_options->depth_scale, "16-bit depth values per metre")
      ->check(positiveNumber())
      ->capture_default_str();
  integrate->add_option("--no-return", integrate_options->no_return,
                        "Depth pixels without a return: drop, or clear (free space up to the map's max range)")
      ->check(CLI::IsMember({"drop", "clear"}))
      ->capture_default_str();
  for (const grid::MapConfigField& field : grid::mapConfigFields()) {
    const std::string unit = *field.unit ? std::string(" [") + field.unit + "]" : "";
    const std::string name = field.name;
    integrate->add_option_function<double>(
                 flagOf(name), [integrate_options, name](double value) { integrate_options->map_config[name] = value; },
                 "A new map's " + name + unit + ": " + field.help + ", " + field.rule + " (default " +
                     nbv::numberText(field.default_value) + "; stored in a .vdb map)")
        ->check(finiteNumber());
  }
  integrate->add_flag("--discretize", integrate_options->discretize,
                      "OctoMap's discretize: one ray per distinct voxel the points end in, to its centre (fewer rays, "
                      "another map; docs/SEMANTICS.md \"The map\")");
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
