#pragma once
/// \file `nbv export`: a map's voxels as a coloured binary PLY (points at voxel centres or cube
/// meshes) that MeshLab, CloudCompare and Open3D open, and candidate views as frusta coloured
/// by their information gain.

#include <CLI/App.hpp>

#include <array>
#include <cstdint>

namespace nbv::apps {

/// The colour of a value in [0, 1] on the viridis scale (0 dark blue, 1 yellow); values outside
/// are clamped. Used by the PLY export and, through the same control points, by the report.
std::array<std::uint8_t, 3> viridis(double t);

/// Adds `export` to `app`.
void addExportCommand(CLI::App& app);

}  // namespace nbv::apps
