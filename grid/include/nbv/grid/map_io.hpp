#pragma once
/// \file Reading and writing maps: OpenVDB `.vdb` (everything) and OctoMap `.ot` / `.bt`.
///
/// What each format carries:
/// - `.vdb`: log-odds of every measured voxel, the proximity marks, and the sensor model and
///   map parameters as grid metadata. Readable by OpenVDB's own tools (vdb_print).
/// - `.ot` (OctoMap OcTree): full log-odds of every measured voxel and the resolution. No
///   proximity marks, no sensor model (an imported map gets the default model).
/// - `.bt` (OctoMap binary): only the maximum-likelihood class of each voxel (occupied or
///   free); probabilities and proximity marks are lost. On import an occupied voxel reads the
///   upper clamp, a free voxel the lower clamp.
///
/// Thread-safety: every function may run in several threads at once on different maps and
/// files (a map being read must not be integrated meanwhile). OctoMap reads and writes take
/// turns: liboctomap prints progress on std::cerr, which they capture for that time.

#include "nbv/grid/occupancy_map.hpp"

#include <filesystem>

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

/// Reads a map. For `.ot`/`.bt` the resolution comes from the file and the rest of the
/// configuration from `base_config`.
/// \throws MapFileError (missing, empty, truncated or malformed file) naming the file.
OccupancyMap loadMap(const std::filesystem::path& path, MapFormat format,
                     const OccupancyMap::Config& base_config = OccupancyMap::Config{});
/// loadMap() with the format taken from the extension.
OccupancyMap loadMap(const std::filesystem::path& path);

}  // namespace nbv::grid
