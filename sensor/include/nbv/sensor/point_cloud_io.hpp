#pragma once
/// \file PLY point clouds: world-frame x y z per vertex.
///
/// Thread-safety: the functions share no state and may run in several threads at once (two writing
/// one file excepted).

#include "nbv/errors.hpp"

#include <Eigen/Core>

#include <filesystem>
#include <string>
#include <vector>

namespace nbv::sensor {

/// Reads the vertices of a PLY file (ascii, binary_little_endian or binary_big_endian) whose
/// vertex element has x, y, z of any PLY scalar type (float and double are usual); other
/// properties and elements are skipped. Coordinates are rounded to single precision.
/// Non-finite coordinates are kept (OccupancyMap::integrate skips them).
/// \throws CloudFileError for a missing, empty, truncated or malformed file.
std::vector<Eigen::Vector3f> readPlyCloud(const std::filesystem::path& path);

/// Writes `points` as a binary little-endian PLY with float x, y, z.
/// \throws CloudFileError if the file cannot be written.
void writePlyCloud(const std::filesystem::path& path, const std::vector<Eigen::Vector3f>& points);

}  // namespace nbv::sensor
