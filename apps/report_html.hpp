#pragma once
/// \file Reports as one self-contained HTML page (three.js inlined from Debian's libjs-three, no
/// network, opens from a file:// URL): the observed points, the candidate views as frusta
/// coloured by their information gain with a slider over the iterations, the chosen path, and
/// the coverage and entropy curves. Used by `nbv report`, `nbv reconstruct --html` and the
/// index of `nbv experiment`.

#include "export_ply.hpp"

#include "nbv/planner/reconstruction.hpp"

#include <CLI/App.hpp>

#include <cstdint>

#include <filesystem>
#include <map>
#include <string>
#include <vector>

namespace nbv::apps {

/// One reconstruction in a report.
struct ReportRun {
  std::string label;  ///< e.g. "pc, seed 0"
  std::vector<planner::IterationRecord> iterations;
  double max_entropy_bits = 0.0;
};

/// What a report page shows.
struct Report {
  std::string title;
  std::vector<planner::View> views;
  std::vector<ReportRun> runs;
  /// Per view a run visits: the points its scan integrates (object and scene), thinned.
  std::map<std::size_t, std::vector<Eigen::Vector3f>> scans;
  /// A map's voxels by class (`nbv report --map`), drawn as points of `voxel_size_m`; the page
  /// has a checkbox per class (free space starts hidden).
  std::vector<VoxelClass> voxels;
  double voxel_size_m = 0.0;
};

/// A run's label in a report: "pc, seed 0". `nbv report` rebuilds the page of
/// `nbv reconstruct --html` from the run's JSON with it, to the same bytes.
std::string runLabel(const std::string& metric, std::uint64_t seed);

/// The title of a page of one run: "bunny: pc, seed 0 (paper)"; a mesh file is named by its stem.
std::string runTitle(const std::string& model, const std::string& metric, std::uint64_t seed, const std::string& scene);

/// Adds to `report` the scan of every view its runs visit, from `object` (each thinned to at
/// most 4,000 points, every k-th).
void addScans(Report& report, const planner::SimulatedObject& object);
/// The same scans rendered from `mesh` (placed) in `config`'s scene with its camera, for a page
/// made without the run's object: only the visited views are rendered, and nothing else done.
void addScans(Report& report, const sensor::TriangleMesh& mesh, const planner::ReconstructionConfig& config);

/// Refuses, before any work, a page that could not be written: three.js missing.
/// \throws FileError naming the missing file and the Debian package that brings it.
void requireThreeJs();

/// Writes the page. \throws FileError if three.js is missing (Debian's libjs-three) or the
/// file cannot be written.
void writeReportHtml(const std::filesystem::path& path, const Report& report);

/// Adds `report` (a run's JSON, as `nbv reconstruct --json` writes it, and/or a map, to an HTML
/// page) to `app`.
void addReportCommand(CLI::App& app);

}  // namespace nbv::apps
