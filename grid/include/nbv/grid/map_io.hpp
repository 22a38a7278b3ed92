#pragma once
/// \file Reading and writing maps: OpenVDB `.vdb` (everything) and OctoMap `.ot` / `.bt`.
///
/// What each format carries:
/// - `.vdb`: log-odds of every measured voxel, the proximity marks, and the sensor model and
///   map parameters as grid metadata. Readable by OpenVDB's own tools (vdb_print).
/// - `.ot` (OctoMap OcTree): full log-odds of every measured voxel and the resolution. No
///   proximity marks, no sensor model (an imported map takes the configuration it is loaded
///   with). Trees of the types `ColorOcTree` (a colour per node, dropped on import) and
///   `OcTreeStamped` (whose files hold no time stamps) are read as well.
/// - `.bt` (OctoMap binary): only the maximum-likelihood class of each voxel (occupied or
///   free); probabilities and proximity marks are lost. On import an occupied voxel reads the
///   upper clamp, a free voxel the lower clamp. On export a voxel is occupied where OctoMap's
///   isNodeOccupied() says so: L >= 0.
///
/// OctoMap prunes a cube of identical voxels into one node; an imported map keeps such a cube
/// as one OpenVDB tile (its voxels read as OctoMap's, each), and a map's tiles are written to
/// `.vdb` as tiles and to `.ot`/`.bt` as pruned nodes. A file is refused before any voxel is
/// set when the map it makes would take more memory than the load's cap
/// (MapLoadOptions::max_bytes).
///
/// Thread-safety: every function may run in several threads at once on different maps and
/// files (a map being read must not be integrated meanwhile). OctoMap reads and writes take
/// turns: liboctomap prints progress on std::cerr, which they capture for that time.

#include "nbv/grid/occupancy_map.hpp"

#include <cstddef>
#include <filesystem>
#include <string>

namespace nbv::grid {

enum class MapFormat { Vdb, OctomapOt, OctomapBt };

/// The format a path names by its extension (.vdb, .ot, .bt; case-insensitive).
/// \throws MapFileError for any other extension.
MapFormat mapFormatFromPath(const std::filesystem::path& path);

/// Writes `map` to `path` in `format`. Writes to `path` directly: callers that must not
/// leave a partial file write to a temporary and rename it.
/// \throws MapFileError if the file cannot be written or the map does not fit the format
/// (OctoMap's 16-bit keys hold indices in [-32768, 32767]).
void saveMap(const OccupancyMap& map, const std::filesystem::path& path, MapFormat format);
/// saveMap() with the format taken from the extension.
void saveMap(const OccupancyMap& map, const std::filesystem::path& path);

/// How loadMap() reads a file.
struct MapLoadOptions {
  /// The configuration of a map read from `.ot`/`.bt`, whose files hold only the resolution
  /// (taken from the file): the sensor model, the ranges (a 6 m scan integrated into a map
  /// loaded with the default 1.5 m range keeps only its first 1.5 m), the classes. A `.vdb`
  /// holds its own.
  OccupancyMap::Config config;
  /// The memory the map's voxel trees may take [bytes], reckoned from the file before any
  /// voxel is set: a few bytes of a pruned OctoMap tree, or of OpenVDB tiles, can describe
  /// billions of voxels.
  std::size_t max_bytes = std::size_t{1} << 30;
};

/// What loadMap() found in a file besides the map.
struct MapLoadReport {
  std::string tree_type;  ///< OctoMap's tree type ("OcTree", "ColorOcTree", "OcTreeStamped"); empty for `.vdb`
  std::string dropped;    ///< what the file holds that the map does not keep (colours); empty if nothing
};

/// Reads a map (the format by the extension) as `options` say; `report`, if given, says what
/// the file held besides. \throws MapFileError (missing, empty, truncated or malformed file,
/// or one that would take more than `options.max_bytes`) naming the file; InvalidArgument for
/// an invalid `options.config`.
OccupancyMap loadMap(const std::filesystem::path& path, const MapLoadOptions& options,
                     MapLoadReport* report = nullptr);

/// Reads a map. For `.ot`/`.bt` the resolution comes from the file and the rest of the
/// configuration from `base_config`.
/// \throws MapFileError (missing, empty, truncated or malformed file) naming the file.
OccupancyMap loadMap(const std::filesystem::path& path, MapFormat format,
                     const OccupancyMap::Config& base_config = OccupancyMap::Config{});
/// loadMap() with the format taken from the extension.
OccupancyMap loadMap(const std::filesystem::path& path);

}  // namespace nbv::grid
