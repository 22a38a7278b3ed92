#pragma once
/// \file The standard workloads of SEMANTICS.md "Standard workloads" and "Real-scale
/// workloads", built the same way for benchmarks, tests and the command line.
///
/// Thread-safety: makeWorkload() shares no state (it runs TBB tasks of its own, and a building's
/// `.bt` round trip goes through a file of its own) and may run in several threads at once.

#include "nbv/grid/occupancy_map.hpp"

#include <Eigen/Core>
#include "nbv/planner/viewspace.hpp"
#include "nbv/sensor/models.hpp"

#include <cstdint>
#include <filesystem>
#include <functional>
#include <string>
#include <string_view>
#include <vector>

namespace nbv::planner {

/// A map and the candidate views to score on it, with the candidates' ray length.
struct Workload {
  std::string name;
  grid::OccupancyMap map;
  std::vector<View> candidates;
  double max_ray_depth_m = 1.5;  ///< the IG rays' length on this workload [m]
};

/// One scan of a workload: its points and the sensor's origin, world frame [m].
struct WorkloadScan {
  std::vector<Eigen::Vector3f> points_world;
  Eigen::Vector3f origin_world;
};

/// Called with each scan of a workload, in order.
using EachScan = std::function<void(const WorkloadScan&)>;

/// One standard workload: a row of kWorkloadTable.
struct WorkloadRow {
  std::string_view name;         ///< "room-2cm"
  std::string_view description;  ///< one line, for help texts
  grid::MapConfig config;         ///< of the map its scans go into
  /// Hands the scans its map is built from to `each`, in order; reads the models it places from
  /// `models`.
  void (*scans)(const std::vector<std::filesystem::path>& models, std::uint64_t seed, const EachScan& each);
  /// The workload from the map of those scans: its candidates, and for a building the map as
  /// OctoMap's binary file gives it back.
  Workload (*finish)(const std::string& name, grid::OccupancyMap scanned);
};

/// The seed of the standard workloads: the same seed gives the same map, bit for bit.
inline constexpr std::uint64_t kDefaultWorkloadSeed = 1;

/// Every standard workload: bunny-3 (the paper's object, 1 cm), room-2cm, building-8cm and
/// building-5cm (SEMANTICS.md "Real-scale workloads").
extern const std::vector<WorkloadRow> kWorkloadTable;

/// The names makeWorkload() knows, in the table's order.
std::vector<std::string> workloadNames();
/// The names joined by ", ": for help texts and errors.
std::string workloadNamesText();

/// Builds a standard workload. `bunny-3`: the bunny (looked for in `models`, as
/// sensor::resolveModel() does) set up as SEMANTICS.md "Simulation and evaluation", a 1 cm map
/// after ideal full-image scans from dome48 views 0, 16 and 33, all 48 views as candidates.
/// `room-2cm`: a closed 6 x 5 x 2.7 m room with furniture and the bunny on a table, 24
/// dataset-like depth frames (noise and holes) along a loop, 2 cm voxels, 4 m range, 48
/// candidates on a sphere inside the room, 4 m rays. `building-8cm` / `building-5cm`: a 32 x 16
/// x 3 m floor of two corridors and 16 furnished rooms, scanned by a four-camera rig from 61
/// places along the corridors and in the rooms, saved as OctoMap `.bt` and read back (every
/// voxel at a clamp), 392 candidates (49 places along the corridors x 8 headings), 6 m rays.
/// Each is deterministic from `seed`.
/// \throws InvalidArgument for an unknown name; nbv::MeshFileError if a model is missing
/// (`nbv models fetch` fetches it).
Workload makeWorkload(const std::string& name,
                      const std::vector<std::filesystem::path>& models = sensor::modelSearchPath(),
                      std::uint64_t seed = kDefaultWorkloadSeed);

/// The row of `name`. \throws InvalidArgument for an unknown name.
const WorkloadRow& workloadRow(const std::string& name);

}  // namespace nbv::planner
