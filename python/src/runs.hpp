#pragma once
// Private to the Python module: what reconstruct() and experiment() share, their settings read
// from the arguments and their runs as dicts.

#include "bindings.hpp"

#include "nbv/planner/reconstruction.hpp"

#include <pybind11/pybind11.h>

#include <cstdint>
#include <memory>
#include <optional>
#include <string>
#include <utility>
#include <variant>
#include <vector>

namespace nbv::python {

/// The settings of a run besides its model, metric and seed, as the arguments gave them.
struct RunSettings {
  planner::ReconstructionConfig config;  ///< metrics and seed left to each run
  std::optional<int> threads;            ///< none: every core
  bool no_timings = false;
  std::string rays;                      ///< "released", "released-shipped", "full" or a pixel stride
  std::string preset;                    ///< the scene preset
  std::string up;                        ///< the up axis of a model loaded by name or path
  std::vector<planner::View> views;
  std::string viewspace;                 ///< "dome48", a view file's absolute path or "array"
};

/// A Python callable as the planner of a run (planner::Planner::Custom, metric=callable):
/// called with the GIL held and the state of the decision as a dict (stateDict), its answer
/// read as a gain per candidate. `planner` is borrowed: the call that runs the reconstruction
/// or experiment holds it.
planner::CandidateScorer pythonScorer(PyObject* planner);

/// A model argument of reconstruct() and experiment().
struct ModelArg {
  std::string given;   ///< as given: the name or path, or "mesh" for an nbv.Mesh
  std::string record;  ///< what a saved run names: a standard name, an absolute path, or "mesh"
  std::string up;      ///< the up axis it is placed with
  std::shared_ptr<Mesh> mesh;
};

/// A ray set's name or a pixel stride.
using RaysGiven = std::variant<int, std::string>;

/// The settings of `iterations`, `rays`, `viewspace` (None, "dome48", a view file's path or an
/// (N, 4, 4) array) and the keyword options of reconstruct(), each of the type the Python
/// layer (nbv/__init__.py) converted it to.
RunSettings runSettings(std::size_t iterations, const RaysGiven& rays, const py::handle& viewspace,
                        const py::dict& options);

/// A model argument: a standard name or a mesh path (loaded and placed with `up`), or an
/// nbv.Mesh (used as it is, recorded by what it was loaded from, placed with its own up axis).
ModelArg modelOf(const ModelGiven& model, const std::string& up);

/// A run as reconstruct() returns it: the fields of `nbv reconstruct --json`, in its order,
/// named `model` and placed with `up`, and the views themselves ("views") when the viewspace
/// was an array; with no_timings, the times of `result` read 0.
py::dict runDict(const std::string& model, const std::string& up, const std::string& metric, std::uint64_t seed,
                 const RunSettings& settings, planner::ReconstructionResult& result);

}  // namespace nbv::python
