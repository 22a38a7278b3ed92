#pragma once
/// \file The standard workloads of SPEC §6, built the same way for benchmarks, tests and the
/// command line.

#include "nbv/grid/occupancy_map.hpp"
#include "nbv/planner/viewspace.hpp"

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

/// Builds a standard workload. `bunny-3`: the bunny of `models_dir` set up as SPEC §5, a 1 cm
/// map after ideal full-image scans from dome48 views 0, 16 and 33, all 48 views as candidates.
/// \throws std::invalid_argument for an unknown name; sensor::MeshFileError if the model is
/// missing (run `make models`).
Workload makeWorkload(const std::string& name, const std::filesystem::path& models_dir);

}  // namespace nbv::planner
