#pragma once
/// \file `nbv export`: a map's voxels as a coloured binary PLY (points at voxel centres or cube
/// meshes) that MeshLab, CloudCompare and Open3D open, and candidate views as frusta coloured
/// by their information gain.

#include "nbv/grid/occupancy_map.hpp"

#include <CLI/App.hpp>

#include <array>
#include <cstdint>
#include <string>
#include <vector>

namespace nbv::apps {

/// The voxels of one class of a map (docs/SEMANTICS.md, "The map"), at their centres [m].
struct VoxelClass {
  std::string name;                    ///< "occupied", "free", "uncertain", "marked", "frontier"
  std::string meaning;                 ///< "P > 0.8", ...
  std::array<std::uint8_t, 3> color;   ///< the class colour of `nbv export --color class`
  std::vector<Eigen::Vector3f> centres;
};

/// Every measured and marked voxel of `map` by class, and the unknown frontier (unmeasured
/// voxels with a face next to a voxel seen empty), in the colours of `nbv export`.
std::vector<VoxelClass> voxelClasses(const grid::OccupancyMap& map);

/// The colour of a value in [0, 1] on the viridis scale (0 dark blue, 1 yellow); values outside
/// are clamped. Used by the PLY export and, through the same control points, by the report.
std::array<std::uint8_t, 3> viridis(double t);

/// Adds `export` to `app`.
void addExportCommand(CLI::App& app);

}  // namespace nbv::apps
