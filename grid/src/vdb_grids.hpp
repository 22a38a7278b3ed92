#pragma once
/// \file Private: the OpenVDB storage behind OccupancyMap, shared by the grid/ sources only.

#include "nbv/grid/occupancy_map.hpp"

#include <openvdb/openvdb.h>

namespace nbv::grid {

/// Log-odds grid (active voxel = measured) and proximity grid (active voxel = marked).
/// Both have background 0 and a transform that puts voxel (i, j, k) at ((i, j, k) + 0.5) *
/// resolution in world space, matching VoxelLattice.
struct OccupancyMap::Grids {
  openvdb::FloatGrid::Ptr log_odds;
  openvdb::Int32Grid::Ptr proximity;
};

inline openvdb::Coord toCoord(const Index3& ijk) { return {ijk.x(), ijk.y(), ijk.z()}; }
inline Index3 toIndex(const openvdb::Coord& c) { return {c.x(), c.y(), c.z()}; }

/// The linear transform of an nbv grid of voxel size `resolution` [m].
openvdb::math::Transform::Ptr makeTransform(double resolution);

/// Calls openvdb::initialize() once (grid type registration for file I/O). Thread-safe.
void initializeOpenVdb();

}  // namespace nbv::grid
