#pragma once
/// \file The standard workloads of SEMANTICS.md "Standard workloads", built the same way for benchmarks, tests and the
/// command line.
///
/// Thread-safety: makeWorkload() shares no state (it runs TBB tasks of its own) and may run in
/// several threads at once.

#include "nbv/grid/occupancy_map.hpp"
#include "nbv/planner/viewspace.hpp"
#include "nbv/sensor/models.hpp"

#include <filesystem>
#include <string>
#include <vector>

namespace nbv::planner {

/// A map and the candidate views to score on it.
struct Workload {
  std::string name;
  grid::OccupancyMap map;
  std::vector<View> candidates;
};

/// The names makeWorkload() knows: "bunny-3".
std::vector<std::string> workloadNames();

/// Builds a standard workload. `bunny-3`: the bunny (looked for in `models`, as
/// sensor::resolveModel() does) set up as SEMANTICS.md "Simulation and evaluation", a 1 cm map
/// after ideal full-image scans from dome48 views 0, 16 and 33, all 48 views as candidates.
/// \throws InvalidArgument for an unknown name; nbv::MeshFileError if the model is
/// missing (`nbv models fetch` fetches it).
Workload makeWorkload(const std::string& name,
                      const std::vector<std::filesystem::path>& models = sensor::modelSearchPath());

}  // namespace nbv::planner
