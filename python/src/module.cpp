// nbv._nbv: the compiled part of the nbv Python package. Its functions take typed arguments
// (pybind11 converts them) and numpy arrays, which arrays.hpp reads and checks by name; the
// package (python/nbv/_signatures.py) gives the functions users call, which check every other
// argument by its kind first and name the one they cannot use.
#include "bindings.hpp"

#include "nbv/errors.hpp"
#include "nbv/kernels/information_gain.hpp"
#include "nbv/kernels/mark_rays.hpp"

namespace nbv::python {

void bindErrors(py::module_& m) {
  // Each nbv exception becomes a Python exception of the same name under the built-in one of
  // the same meaning; bases first, so that a subclass's translator is tried before its base's.
  auto invalid = py::register_exception<InvalidArgument>(m, "InvalidArgument", PyExc_ValueError);
  invalid.doc() = "A value nbv cannot use (a shape, a dtype, an option, a pose): a ValueError.";
  auto capacity = py::register_exception<CapacityError>(m, "CapacityError", PyExc_MemoryError);
  capacity.doc() = "A configured cap an operation would exceed (map voxels, snapshot memory): a MemoryError.";
  auto file = py::register_exception<FileError>(m, "FileError", PyExc_OSError);
  file.doc() = "A file nbv cannot read or write; the message names it: an OSError.";
  py::register_exception<MapFileError>(m, "MapFileError", file.ptr()).doc() = "A map file (.vdb, .ot, .bt) that cannot be read or written: an nbv.FileError.";
  py::register_exception<CloudFileError>(m, "CloudFileError", file.ptr()).doc() = "A point cloud (PLY) that cannot be read or written: an nbv.FileError.";
  py::register_exception<MeshFileError>(m, "MeshFileError", file.ptr()).doc() = "A mesh file that cannot be loaded or used: an nbv.FileError.";
  py::register_exception<ViewFileError>(m, "ViewFileError", file.ptr()).doc() = "A view file (N, then x y z qx qy qz qw lines) that cannot be read or written: an nbv.FileError.";
  py::register_exception<SceneError>(m, "SceneError", PyExc_RuntimeError).doc() = "An error the ray-casting library (Embree) reported: a RuntimeError.";
}

}  // namespace nbv::python

PYBIND11_MODULE(_nbv, m) {
  // Each docstring opens with its Python signature, defaults and return type as a caller writes
  // them: the package's functions take these docstrings, and pybind11's own signature would name
  // the compiled one's C++ types.
  pybind11::options options;
  options.disable_function_signatures();
  m.doc() = "The compiled part of nbv; import nbv instead.";
  m.attr("__version__") = NBV_VERSION;
  m.attr("isa") = nbv::kernels::isaName(nbv::kernels::bestIsa());
  pybind11::tuple metrics(nbv::kernels::kAllMetrics.size());
  for (std::size_t i = 0; i < metrics.size(); ++i) metrics[i] = nbv::kernels::metricName(nbv::kernels::kAllMetrics[i]);
  m.attr("METRICS") = metrics;
  nbv::python::bindErrors(m);
  nbv::python::bindMap(m);
  nbv::python::bindSensor(m);
  nbv::python::bindInformationGain(m);
  nbv::python::bindPlanner(m);
  nbv::python::bindExperiment(m);
}
