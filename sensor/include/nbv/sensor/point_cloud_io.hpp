#pragma once
/// \file PLY point clouds: world-frame x y z per vertex.

#include <Eigen/Core>

#include <filesystem>
#include <stdexcept>
#include <string>
#include <vector>

namespace nbv::sensor {

/// A point cloud file that cannot be read or written; what() names the file (and the header
/// line, where there is one) and the problem.
class CloudFileError : public std::runtime_error {
 public:
  CloudFileError(const std::filesystem::path& path, const std::string& problem)
      : std::runtime_error(path.string() + ": " + problem), path_(path) {}
  const std::filesystem::path& path() const { return path_; }

 private:
  std::filesystem::path path_;
};

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
