#include "arrays.hpp"

#include "nbv/errors.hpp"

#include <cmath>
#include <sstream>

namespace nbv::python {

namespace {

std::string shapeText(const py::array& a) {
  std::ostringstream text;
  text << '(';
  for (py::ssize_t d = 0; d < a.ndim(); ++d) text << (d ? ", " : "") << a.shape(d);
  text << (a.ndim() == 1 ? ",)" : ")");
  return text.str();
}

/// The object as a numpy array (converted if it is a sequence), refusing others by name.
py::array numpyArray(const py::handle& object, const char* name) {
  py::array a;
  try {
    a = py::array::ensure(object);
  } catch (const py::error_already_set&) {
  }
  if (!a) throw InvalidArgument(std::string(name) + ": not convertible to a numpy array");
  return a;
}

/// The object as a numpy array of floating dtype, refusing other dtypes by name.
py::array floatingArray(const py::handle& object, const char* name) {
  py::array a = numpyArray(object, name);
  if (a.dtype().kind() != 'f') {
    throw InvalidArgument(std::string(name) + ": dtype " + std::string(py::str(a.dtype())) +
                          " is not a floating type (give float32 or float64)");
  }
  return a;
}

template <class Vector>
Rows<Vector> rowsOf(const py::handle& object, const char* name) {
  using Scalar = typename Vector::Scalar;
  static_assert(sizeof(Vector) == 3 * sizeof(Scalar), "Eigen 3-vectors are packed");
  py::array a = floatingArray(object, name);
  if (a.ndim() != 2 || a.shape(1) != 3) {
    throw InvalidArgument(std::string(name) + ": shape " + shapeText(a) + " is not (N, 3)");
  }
  // The caller's array itself when it has the type and C order; otherwise one converted copy.
  py::array_t<Scalar, py::array::c_style | py::array::forcecast> rows = py::array_t<Scalar, py::array::c_style | py::array::forcecast>::ensure(a);
  if (!rows) throw InvalidArgument(std::string(name) + ": cannot be read as " + (sizeof(Scalar) == 4 ? "float32" : "float64"));
  const auto* data = reinterpret_cast<const Vector*>(rows.data());
  return {rows, std::span<const Vector>(data, static_cast<std::size_t>(rows.shape(0)))};
}

}  // namespace

Rows<Eigen::Vector3f> pointsFloat(const py::handle& object, const char* name) { return rowsOf<Eigen::Vector3f>(object, name); }

Rows<Eigen::Vector3d> pointsDouble(const py::handle& object, const char* name) { return rowsOf<Eigen::Vector3d>(object, name); }

Eigen::Vector3d vector3(const py::handle& object, const char* name) {
  // One point or direction: integers convert exactly, so (0, 0, 1) reads as (0.0, 0.0, 1.0).
  const py::array a = numpyArray(object, name);
  if (const char kind = a.dtype().kind(); kind != 'f' && kind != 'i' && kind != 'u') {
    throw InvalidArgument(std::string(name) + ": dtype " + std::string(py::str(a.dtype())) +
                          " is not a number type (give floats or integers)");
  }
  if (a.ndim() != 1 || a.shape(0) != 3) throw InvalidArgument(std::string(name) + ": shape " + shapeText(a) + " is not (3,)");
  const auto v = py::array_t<double, py::array::forcecast>::ensure(a);
  const Eigen::Vector3d out(v.at(0), v.at(1), v.at(2));
  if (!out.allFinite()) {
    std::ostringstream text;
    text << name << ": (" << out.x() << ", " << out.y() << ", " << out.z() << ") is not finite";
    throw InvalidArgument(text.str());
  }
  return out;
}

std::vector<Eigen::Isometry3d> poses(const py::handle& object, const char* name) {
  const py::array a = floatingArray(object, name);
  const bool one = a.ndim() == 2;
  if (!((one || a.ndim() == 3) && a.shape(a.ndim() - 2) == 4 && a.shape(a.ndim() - 1) == 4)) {
    throw InvalidArgument(std::string(name) + ": shape " + shapeText(a) + " is not (N, 4, 4) or (4, 4)");
  }
  const auto m = py::array_t<double, py::array::c_style | py::array::forcecast>::ensure(a);
  const std::size_t n = one ? 1 : static_cast<std::size_t>(m.shape(0));
  if (n == 0) throw InvalidArgument(std::string(name) + ": no view given (an empty (0, 4, 4) array)");
  std::vector<Eigen::Isometry3d> out(n);
  for (std::size_t i = 0; i < n; ++i) {
    // numpy is row-major: map the 16 numbers as a row-major 4 x 4.
    const Eigen::Map<const Eigen::Matrix<double, 4, 4, Eigen::RowMajor>> T(m.data() + 16 * i);
    const Eigen::Matrix3d R = T.topLeftCorner<3, 3>();
    const bool rigid = T.allFinite() && T.row(3).isApprox(Eigen::RowVector4d(0, 0, 0, 1), 0.0) &&
                       (R.transpose() * R - Eigen::Matrix3d::Identity()).cwiseAbs().maxCoeff() < 1e-6 &&
                       R.determinant() > 0.0;
    if (!rigid) {
      // A single (4, 4) pose is named as given, without an index it does not have.
      throw InvalidArgument(std::string(name) + (one ? "" : "[" + std::to_string(i) + "]") +
                            " is not a finite rigid transform (rotation with det +1, last row 0 0 0 1)");
    }
    out[i].matrix() = T;
  }
  return out;
}

Eigen::Isometry3d pose(const py::handle& object, const char* name) {
  const py::array a = floatingArray(object, name);
  if (a.ndim() != 2) throw InvalidArgument(std::string(name) + ": shape " + shapeText(a) + " is not (4, 4)");
  return poses(a, name).front();
}

py::array_t<double> posesArray(const std::vector<planner::View>& views) {
  std::vector<double> data(views.size() * 16);
  for (std::size_t i = 0; i < views.size(); ++i) {
    Eigen::Map<Eigen::Matrix<double, 4, 4, Eigen::RowMajor>>(data.data() + 16 * i) = views[i].T_world_camera.matrix();
  }
  return ownedArray(std::move(data), {static_cast<py::ssize_t>(views.size()), 4, 4});
}

std::vector<planner::View> viewsOf(const py::handle& object, const char* name) {
  std::vector<planner::View> views;
  for (const Eigen::Isometry3d& T : poses(object, name)) views.push_back({T});
  return views;
}

}  // namespace nbv::python
