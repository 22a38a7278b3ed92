#include "nbv/planner/evaluation.hpp"

#include "nbv/kernels/information_gain.hpp"

#include "nbv/errors.hpp"

#include <nanoflann.hpp>

#include <cmath>
#include <string>

namespace nbv::planner {

namespace {

/// nanoflann's view of the ground-truth points: their buffer, which stays where it is when
/// the vector holding it is moved (a SurfaceCoverage may be moved; its vector's address changes).
struct PointSet {
  std::span<const Eigen::Vector3f> points;
  std::size_t kdtree_get_point_count() const { return points.size(); }
  float kdtree_get_pt(std::size_t i, std::size_t dim) const { return points[i][static_cast<int>(dim)]; }
  template <class Box>
  bool kdtree_get_bbox(Box&) const {
    return false;
  }
};

using KdTree = nanoflann::KDTreeSingleIndexAdaptor<nanoflann::L2_Simple_Adaptor<float, PointSet>, PointSet, 3>;

}  // namespace

struct SurfaceCoverage::Index {
  explicit Index(const std::vector<Eigen::Vector3f>& points)
      : set{points}, tree(3, set, nanoflann::KDTreeSingleIndexAdaptorParams(16)) {
    tree.buildIndex();
  }
  PointSet set;
  KdTree tree;
};

SurfaceCoverage::SurfaceCoverage(std::vector<Eigen::Vector3f> ground_truth, double registration_distance_m)
    : ground_truth_(std::move(ground_truth)), registration_distance_m_(registration_distance_m) {
  if (ground_truth_.empty()) throw InvalidArgument("surface coverage needs ground-truth points");
  if (!(registration_distance_m_ > 0.0) || !std::isfinite(registration_distance_m_)) {
    throw InvalidArgument("registration distance " + std::to_string(registration_distance_m_) +
                                " m must be positive");
  }
  covered_.assign(ground_truth_.size(), false);
  index_ = std::make_unique<Index>(ground_truth_);
}

SurfaceCoverage::~SurfaceCoverage() = default;
SurfaceCoverage::SurfaceCoverage(SurfaceCoverage&&) noexcept = default;
SurfaceCoverage& SurfaceCoverage::operator=(SurfaceCoverage&&) noexcept = default;

void SurfaceCoverage::addScan(std::span<const Eigen::Vector3f> observed_world) {
  // L2_Simple_Adaptor works in squared distances.
  const auto radius_sq = static_cast<float>(registration_distance_m_ * registration_distance_m_);
  std::vector<std::pair<std::uint32_t, float>> hits;
  nanoflann::SearchParams params;
  params.sorted = false;
  for (const Eigen::Vector3f& p : observed_world) {
    if (!p.allFinite()) continue;
    hits.clear();
    index_->tree.radiusSearch(p.data(), radius_sq, hits, params);
    for (const auto& [i, distance_sq] : hits) {
      if (!covered_[i]) {
        covered_[i] = true;
        ++covered_count_;
      }
    }
  }
}

double SurfaceCoverage::coverage() const {
  return static_cast<double>(covered_count_) / static_cast<double>(ground_truth_.size());
}

namespace {
int voxelsPerSide(const grid::OccupancyMap& map, double edge_m) {
  const double n = std::round(edge_m / map.config().resolution);
  if (!(n >= 1.0 && n <= 4096.0)) {
    throw InvalidArgument("entropy cube of " + std::to_string(edge_m) + " m holds " + std::to_string(n) +
                                " voxels per side; expected 1 to 4096");
  }
  return static_cast<int>(n);
}
}  // namespace

double mapEntropyBits(const grid::OccupancyMap& map, const Eigen::Vector3d& centre_world, double edge_m) {
  const int n = voxelsPerSide(map, edge_m);
  const grid::Index3 first = map.worldToIndex(centre_world) - grid::Index3::Constant(n / 2);
  double bits = 0.0;
  std::size_t measured = 0;
  for (const grid::MeasuredVoxel& voxel : map.measuredVoxels()) {
    const grid::Index3 local = voxel.ijk - first;
    if ((local.array() < 0).any() || (local.array() >= n).any()) continue;
    bits += kernels::entropyNats(grid::OccupancyMap::probabilityOf(voxel.log_odds)) / std::log(2.0);
    ++measured;
  }
  return bits + (maxMapEntropyBits(map, edge_m) - static_cast<double>(measured));  // 1 bit per unmeasured voxel
}

double maxMapEntropyBits(const grid::OccupancyMap& map, double edge_m) {
  const double n = voxelsPerSide(map, edge_m);
  return n * n * n;
}

double areaUnderCurve(std::span<const double> values, double value_at_zero, double maximum) {
  if (!(maximum > 0.0)) throw InvalidArgument("areaUnderCurve: the maximum must be positive");
  if (values.empty()) return 0.0;
  double area = 0.0, previous = value_at_zero;
  for (double v : values) {  // trapezoids of width 1 / N
    area += 0.5 * (previous + v);
    previous = v;
  }
  return area / static_cast<double>(values.size()) / maximum;
}

}  // namespace nbv::planner
