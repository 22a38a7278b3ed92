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
#include <optional>
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
/// An (N, 4, 4) float array of rigid T_world_camera poses, N >= 1; a single (4, 4) pose is N = 1.
std::vector<Eigen::Isometry3d> poses(const py::handle& object, const char* name);
/// One (4, 4) rigid pose.
Eigen::Isometry3d pose(const py::handle& object, const char* name);

/// The poses of views as an (N, 4, 4) float64 array.
py::array_t<double> posesArray(const std::vector<planner::View>& views);
/// Views of an (N, 4, 4) array.
std::vector<planner::View> viewsOf(const py::handle& object, const char* name);

/// What a value of type T is, for the error message of optionValue().
template <class T>
struct OptionType {
  static std::string expected() {
    if constexpr (std::is_same_v<T, bool>) {
      return "True or False";
    } else if constexpr (std::is_integral_v<T>) {
      const std::string kind = std::is_unsigned_v<T> ? "a non-negative int" : "an int";
      return sizeof(T) == 4 ? kind + " that fits 32 bits" : kind;
    } else if constexpr (std::is_floating_point_v<T>) {
      return "a number";
    } else if constexpr (std::is_same_v<T, std::string>) {
      return "a string";
    } else if constexpr (std::is_same_v<T, std::vector<std::string>>) {
      return "a sequence of strings";
    } else if constexpr (std::is_same_v<T, std::vector<std::uint64_t>>) {
      return "a sequence of non-negative ints";
    } else {
      static_assert(std::is_same_v<T, std::vector<double>>, "an option type without a description");
      return "a sequence of numbers";
    }
  }
};
template <class T>
struct OptionType<std::optional<T>> {
  static std::string expected() { return "None or " + OptionType<T>::expected(); }
};

/// repr(value) on one line (each run of white space one space), cut to 80 characters: an
/// array's repr runs to many lines and thousands of characters.
inline std::string shortRepr(const py::handle& value) {
  const std::string full = py::repr(value);
  std::string text;
  for (const char c : full) {
    const bool space = c == ' ' || c == '\n' || c == '\t' || c == '\r';
    if (!space) text += c;
    else if (text.empty() || text.back() != ' ') text += ' ';
  }
  return text.size() <= 80 ? text : text.substr(0, 77) + "...";
}

/// A value found inside an argument (a field of a run's dict, a callback's answer) as T
/// (std::optional<T>: None or a T); the arguments themselves are converted by the Python layer
/// (nbv/_arguments.py). \throws InvalidArgument naming `option` ("table1: runs[0]['seed']"), the
/// value and the type expected, where pybind11 would say only "Unable to cast".
template <class T>
T optionValue(const py::handle& value, const std::string& option) {
  try {
    return value.cast<T>();
  } catch (const py::cast_error&) {
    throw InvalidArgument(option + " = " + shortRepr(value) + " is not " + OptionType<T>::expected());
  }
}

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
