#pragma once
/// \file Typed exceptions of nbv::sensor. Library code throws these and never prints or aborts.

#include <filesystem>
#include <stdexcept>
#include <string>

namespace nbv::sensor {

/// A file the sensor module cannot use; what() names the file and the problem.
class FileError : public std::runtime_error {
 public:
  FileError(const std::filesystem::path& path, const std::string& problem)
      : std::runtime_error(path.string() + ": " + problem), path_(path) {}
  const std::filesystem::path& path() const { return path_; }

 private:
  std::filesystem::path path_;
};

/// A point cloud (PLY) that cannot be read or written.
class CloudFileError : public FileError {
 public:
  using FileError::FileError;
};

/// A mesh that cannot be loaded or used.
class MeshFileError : public FileError {
 public:
  using FileError::FileError;
};

}  // namespace nbv::sensor
