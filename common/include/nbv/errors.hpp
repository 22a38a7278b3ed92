#pragma once
/// \file Every exception type nbv throws, in one place. Library code throws these (and
/// std::bad_alloc when memory runs out) and never prints or aborts; what() is one line a user
/// can act on: the file and line, or the value and what it should be.
///
/// The hierarchy keeps the standard bases, so `catch (const std::invalid_argument&)` still
/// catches a bad value, and the Python package maps each type onto the built-in exception of
/// the same meaning (InvalidArgument -> ValueError, CapacityError -> MemoryError, FileError ->
/// OSError).

#include <charconv>
#include <filesystem>
#include <stdexcept>
#include <string>
#include <type_traits>

namespace nbv {

/// A number as messages print it: the shortest text that reads back as the same value, in
/// printf's %g style ("0.01", "0.0001", "2.5e-07", "nan"), not std::to_string's six decimals
/// ("0.010000", "0.000000").
template <class Real>
std::string numberText(Real value) {
  static_assert(std::is_floating_point_v<Real>);
  char text[32];
  return std::string(text, std::to_chars(text, text + sizeof text, value, std::chars_format::general).ptr);
}

/// A value given to nbv (an option, a pose, a ray, an index, an array) that it cannot use.
class InvalidArgument : public std::invalid_argument {
 public:
  using std::invalid_argument::invalid_argument;
};

/// A configured resource cap that an operation would exceed (the map's measured voxels, the
/// evaluator's snapshot memory); the operation is refused before it changes anything.
class CapacityError : public std::runtime_error {
 public:
  using std::runtime_error::runtime_error;
};

/// A file that cannot be read or written; what() is "<path>: <problem>".
class FileError : public std::runtime_error {
 public:
  FileError(const std::filesystem::path& path, const std::string& problem)
      : std::runtime_error(path.string() + ": " + problem), path_(path) {}
  const std::filesystem::path& path() const { return path_; }

 private:
  std::filesystem::path path_;
};

/// A map file (.vdb, .ot, .bt).
class MapFileError : public FileError {
 public:
  using FileError::FileError;
};

/// A point cloud (PLY).
class CloudFileError : public FileError {
 public:
  using FileError::FileError;
};

/// A mesh file, or a mesh that cannot be used.
class MeshFileError : public FileError {
 public:
  using FileError::FileError;
};

/// A view file (`N`, then N lines `x y z qx qy qz qw`).
class ViewFileError : public FileError {
 public:
  using FileError::FileError;
};

/// An error the ray-casting library (Embree) reported, with its message.
class SceneError : public std::runtime_error {
 public:
  using std::runtime_error::runtime_error;
};

}  // namespace nbv
