#pragma once
/// \file Typed exceptions of nbv::grid. Library code throws these and never prints or aborts.

#include <filesystem>
#include <stdexcept>
#include <string>

namespace nbv::grid {

/// A value given to the map (configuration, origin, voxel index) that it cannot use.
class InvalidArgument : public std::invalid_argument {
 public:
  using std::invalid_argument::invalid_argument;
};

/// A configured resource cap that an operation would exceed (map voxels, evaluation memory);
/// the operation is refused before it changes anything.
class CapacityError : public std::runtime_error {
 public:
  using std::runtime_error::runtime_error;
};

/// A map file that cannot be read or written; what() names the file and the problem.
class MapFileError : public std::runtime_error {
 public:
  MapFileError(const std::filesystem::path& path, const std::string& problem)
      : std::runtime_error(path.string() + ": " + problem), path_(path) {}
  const std::filesystem::path& path() const { return path_; }

 private:
  std::filesystem::path path_;
};

}  // namespace nbv::grid
