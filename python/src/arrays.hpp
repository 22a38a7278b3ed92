#pragma once
// Private to the Python module: numpy arrays in and out, checked once at the boundary. A bad
// array throws nbv::InvalidArgument (Python: nbv.InvalidArgument, a ValueError) naming the
// argument, its shape or dtype, and what was expected.

#include "nbv/errors.hpp"
#include "nbv/planner/viewspace.hpp"

#include <Eigen/Core>
#include <Eigen/Geometry>
#include <pybind11/numpy.h>
#include <pybind11/pybind11.h>

#include <cstddef>
#include <memory>
#include <span>
#include <string>
#include <type_traits>
#include <vector>

namespace nbv::python {

namespace py = pybind11;

/// Rows of three coordinates that C++ reads in place: `rows` points into `holder`, which is
/// the caller's own array when it already had the element type and C order, else a copy.
template <class Vector>
struct Rows {
  py::array holder;
  std::span<const Vector> rows;
};

/// An (N, 3) floating array as single-precision points (no copy for C-contiguous float32).
Rows<Eigen::Vector3f> pointsFloat(const py::handle& object, const char* name);
/// An (N, 3) floating array as double-precision vectors (no copy for C-contiguous float64).
Rows<Eigen::Vector3d> pointsDouble(const py::handle& object, const char* name);
/// A finite (3,) vector of floats or integers.
Eigen::Vector3d vector3(const py::handle& object, const char* name);
/// An (N, 4, 4) float array of rigid T_world_camera poses; a single (4, 4) pose is N = 1.
std::vector<Eigen::Isometry3d> poses(const py::handle& object, const char* name);
/// One (4, 4) rigid pose.
Eigen::Isometry3d pose(const py::handle& object, const char* name);

/// The poses of views as an (N, 4, 4) float64 array.
py::array_t<double> posesArray(const std::vector<planner::View>& views);
/// Views of an (N, 4, 4) array.
std::vector<planner::View> viewsOf(const py::handle& object, const char* name);

/// A keyword option's value as T. \throws InvalidArgument naming `option` ("DepthCamera:
/// width"), the value and the type expected, where pybind11 would say only "Unable to cast".
template <class T>
T optionValue(const py::handle& value, const std::string& option) {
  try {
    return value.cast<T>();
  } catch (const py::cast_error&) {
    const char* expected = std::is_same_v<T, bool>          ? "True or False"
                           : std::is_integral_v<T>          ? (sizeof(T) == 4 ? "an int that fits 32 bits" : "an int")
                           : std::is_floating_point_v<T>    ? "a number"
                           : std::is_same_v<T, std::string> ? "a string"
                           : std::is_same_v<T, std::vector<std::string>> ? "a sequence of strings"
                                                                         : "a sequence of numbers";
    throw InvalidArgument(option + " = " + std::string(py::repr(value)) + " is not " + expected);
  }
}

/// The keyword options of one function or class, read by key: option.as<double>(value, "gamma")
/// names "reconstruct: gamma" in its error.
struct KeywordOptions {
  std::string owner;
  template <class T>
  T as(const py::handle& value, const std::string& key) const {
    return optionValue<T>(value, owner + ": " + key);
  }
};

/// A numpy array that owns `data`, moved in (no copy), of the given shape.
template <class T>
py::array_t<T> ownedArray(std::vector<T>&& data, std::vector<py::ssize_t> shape) {
  auto* heap = new std::vector<T>(std::move(data));
  py::capsule owner(heap, [](void* p) { delete static_cast<std::vector<T>*>(p); });
  return py::array_t<T>(shape, heap->data(), owner);
}

/// A vector of 3-vectors as an (N, 3) array, moved in.
template <class Scalar>
py::array_t<Scalar> ownedRows(std::vector<Eigen::Matrix<Scalar, 3, 1>>&& rows) {
  static_assert(sizeof(Eigen::Matrix<Scalar, 3, 1>) == 3 * sizeof(Scalar), "packed rows");
  auto* heap = new std::vector<Eigen::Matrix<Scalar, 3, 1>>(std::move(rows));
  py::capsule owner(heap, [](void* p) { delete static_cast<std::vector<Eigen::Matrix<Scalar, 3, 1>>*>(p); });
  const auto n = static_cast<py::ssize_t>(heap->size());
  return py::array_t<Scalar>({n, py::ssize_t{3}}, heap->empty() ? nullptr : heap->front().data(), owner);
}

}  // namespace nbv::python
