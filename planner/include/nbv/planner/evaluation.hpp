#pragma once
/// \file How a reconstruction is scored (paper Sec. 4, SEMANTICS.md "Simulation and evaluation"): surface coverage (Eq. 15), map
/// entropy (Eq. 16), and the area under their curves.

#include "nbv/grid/occupancy_map.hpp"

#include <Eigen/Core>

#include <cstddef>
#include <cstdint>
#include <memory>
#include <span>
#include <vector>

namespace nbv::planner {

/// Ground-truth surface points in a KD-tree (nanoflann): built once per object and shared by
/// every run on it. Immutable; thread-safe.
class GroundTruth {
 public:
  /// \throws InvalidArgument if `points` is empty or the distance is not positive.
  GroundTruth(std::vector<Eigen::Vector3f> points, double registration_distance_m = 0.005);
  ~GroundTruth();
  GroundTruth(const GroundTruth&) = delete;
  GroundTruth& operator=(const GroundTruth&) = delete;

  std::span<const Eigen::Vector3f> points() const { return points_; }
  double registrationDistance() const { return registration_distance_m_; }
  /// The indices, ascending and each once, of the points that have a point of `observed_world`
  /// within the registration distance (non-finite observed points are ignored): one radius
  /// search per observed point.
  std::vector<std::uint32_t> coveredBy(std::span<const Eigen::Vector3f> observed_world) const;

 private:
  struct Index;
  std::vector<Eigen::Vector3f> points_;
  double registration_distance_m_;
  std::unique_ptr<Index> index_;
};

/// Eq. 15: the fraction of ground-truth surface points that have an observed point within the
/// registration distance, over all scans added so far. Not thread-safe (each run has its own;
/// they may share one GroundTruth).
class SurfaceCoverage {
 public:
  explicit SurfaceCoverage(std::shared_ptr<const GroundTruth> ground_truth);
  /// A coverage over its own ground truth. \throws InvalidArgument as GroundTruth().
  SurfaceCoverage(std::vector<Eigen::Vector3f> ground_truth, double registration_distance_m = 0.005);

  /// Adds the world points of one scan (non-finite points are ignored).
  void addScan(std::span<const Eigen::Vector3f> observed_world);
  /// Adds what GroundTruth::coveredBy() found for a scan. \throws InvalidArgument for an index
  /// out of range.
  void addCovered(std::span<const std::uint32_t> indices);
  /// The coverage a scan that covers `indices` (ascending, each once, as coveredBy() gives them)
  /// would add: the share of ground-truth points among them not covered yet, in [0, 1]. What the
  /// oracle scores a candidate by (SEMANTICS.md "The oracle"). \throws InvalidArgument for an
  /// index out of range.
  double gainOf(std::span<const std::uint32_t> indices) const;
  /// Covered fraction in [0, 1].
  double coverage() const;
  std::size_t coveredPoints() const { return covered_count_; }
  std::size_t groundTruthPoints() const { return covered_.size(); }

 private:
  std::shared_ptr<const GroundTruth> ground_truth_;
  std::vector<bool> covered_;
  std::size_t covered_count_ = 0;
};

/// Eq. 16 as SEMANTICS.md "Simulation and evaluation" settles it: the sum of voxel entropies in bits over the cube of
/// `edge_m` (default 1.28 m: 128^3 voxels at 1 cm) centred on `centre_world`, the voxel of the
/// centre at index (n / 2) of the n voxels per side; unmeasured voxels count 1 bit each.
double mapEntropyBits(const grid::OccupancyMap& map, const Eigen::Vector3d& centre_world, double edge_m = 1.28);

/// The largest value mapEntropyBits() can return for that cube: one bit per voxel.
double maxMapEntropyBits(const grid::OccupancyMap& map, double edge_m = 1.28);

/// Area under a curve of `values` at iterations 1..N, with `value_at_zero` at iteration 0, by
/// the trapezoidal rule over x normalised to [0, 1], divided by `maximum` (SEMANTICS.md "Simulation and evaluation"). 0 for no
/// values. \throws InvalidArgument if `maximum` is not positive.
double areaUnderCurve(std::span<const double> values, double value_at_zero, double maximum);

}  // namespace nbv::planner
