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
#include <vector>

namespace nbv::python {

/// The settings of a run besides its model, metric and seed, as the arguments gave them.
struct RunSettings {
  planner::ReconstructionConfig config;  ///< metrics and seed left to each run
  std::optional<int> threads;            ///< none: every core
  bool no_timings = false;
  std::string rays;                      ///< "released", "full" or a pixel stride
  std::string preset;                    ///< the scene preset
  std::string up;                        ///< the up axis of a model loaded by name or path
  std::vector<planner::View> views;
  std::string viewspace;                 ///< "dome48", a view file's path or "array"
};

/// Reads `iterations`, `rays`, `viewspace` and the keyword options of reconstruct() (refusing
/// unknown ones by name), errors naming `owner`.
RunSettings runSettings(const std::string& owner, const py::handle& iterations, const py::handle& rays,
                        const py::handle& viewspace, const py::kwargs& options);

/// A model argument: a standard name or a mesh path (loaded and placed with `up`, named as
/// given), or an nbv.Mesh (used as given, named "mesh"). \throws InvalidArgument naming `where`.
std::pair<std::string, std::shared_ptr<Mesh>> modelOf(const py::handle& model, const std::string& up,
                                                      const std::string& where);

/// A run as reconstruct() returns it: the fields of `nbv reconstruct --json`, in its order;
/// with no_timings, the times of `result` read 0.
py::dict runDict(const std::string& model, const std::string& metric, std::uint64_t seed, const RunSettings& settings,
                 planner::ReconstructionResult& result);

}  // namespace nbv::python
