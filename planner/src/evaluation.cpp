#include "nbv/planner/evaluation.hpp"

#include "nbv/kernels/information_gain.hpp"

#include "nbv/errors.hpp"

#include <nanoflann.hpp>

#include <algorithm>
#include <bit>
#include <cmath>
#include <cstdint>
#include <limits>
#include <optional>
#include <string>
#include <span>
#include <unordered_map>
#include <vector>

namespace nbv::planner {

namespace {

/// nanoflann's view of the ground-truth points: their buffer.
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

struct GroundTruth::Index {
  explicit Index(std::span<const Eigen::Vector3f> points)
      : set{points}, tree(3, set, nanoflann::KDTreeSingleIndexAdaptorParams(16)) {
    tree.buildIndex();
  }
  PointSet set;
  KdTree tree;
};

GroundTruth::GroundTruth(std::vector<Eigen::Vector3f> points, double registration_distance_m)
    : points_(std::move(points)), registration_distance_m_(registration_distance_m) {
  if (points_.empty()) throw InvalidArgument("surface coverage needs ground-truth points");
  if (!(registration_distance_m_ > 0.0) || !std::isfinite(registration_distance_m_)) {
    throw InvalidArgument("registration distance " + std::to_string(registration_distance_m_) + " m must be positive");
  }
  index_ = std::make_unique<Index>(points_);
}

GroundTruth::~GroundTruth() = default;

std::vector<std::uint32_t> GroundTruth::coveredBy(std::span<const Eigen::Vector3f> observed_world) const {
  // L2_Simple_Adaptor works in squared distances.
  const auto radius_sq = static_cast<float>(registration_distance_m_ * registration_distance_m_);
  std::vector<bool> covered(points_.size(), false);
  std::vector<std::pair<std::uint32_t, float>> hits;
  nanoflann::SearchParams params;
  params.sorted = false;
  for (const Eigen::Vector3f& p : observed_world) {
    if (!p.allFinite()) continue;
    hits.clear();
    index_->tree.radiusSearch(p.data(), radius_sq, hits, params);
    for (const auto& hit : hits) covered[hit.first] = true;
  }
  std::vector<std::uint32_t> indices;
  for (std::size_t i = 0; i < covered.size(); ++i) {
    if (covered[i]) indices.push_back(static_cast<std::uint32_t>(i));
  }
  return indices;
}

SurfaceCoverage::SurfaceCoverage(std::shared_ptr<const GroundTruth> ground_truth)
    : ground_truth_(std::move(ground_truth)) {
  if (!ground_truth_) throw InvalidArgument("surface coverage needs a ground truth");
  covered_.assign(ground_truth_->points().size(), false);
}

SurfaceCoverage::SurfaceCoverage(std::vector<Eigen::Vector3f> ground_truth, double registration_distance_m)
    : SurfaceCoverage(std::make_shared<const GroundTruth>(std::move(ground_truth), registration_distance_m)) {}

void SurfaceCoverage::addScan(std::span<const Eigen::Vector3f> observed_world) {
  addCovered(ground_truth_->coveredBy(observed_world));
}

void SurfaceCoverage::addCovered(std::span<const std::uint32_t> indices) {
  for (const std::uint32_t i : indices) {
    if (i >= covered_.size()) throw InvalidArgument("ground-truth index " + std::to_string(i) + " out of range");
    if (!covered_[i]) {
      covered_[i] = true;
      ++covered_count_;
    }
  }
}

double SurfaceCoverage::gainOf(std::span<const std::uint32_t> indices) const {
  std::size_t added = 0;
  for (const std::uint32_t i : indices) {
    if (i >= covered_.size()) throw InvalidArgument("ground-truth index " + std::to_string(i) + " out of range");
    added += covered_[i] ? 0 : 1;
  }
  return static_cast<double>(added) / static_cast<double>(covered_.size());
}

double SurfaceCoverage::coverage() const {
  return static_cast<double>(covered_count_) / static_cast<double>(covered_.size());
}

namespace {
int voxelsPerSide(const grid::OccupancyMap& map, double edge_m) {
  const double n = std::round(edge_m / map.config().resolution);
  if (!(n >= 1.0 && n <= 4096.0)) {
    throw InvalidArgument("entropy cube of " + numberText(edge_m) + " m holds " + numberText(n) + " voxels per side at " +
                          numberText(map.config().resolution) + " m; expected 1 to 4096");
  }
  return static_cast<int>(n);
}

/// Eq. 16's sum over measured log-odds values given in (i, j, k) order. Each distinct value's
/// entropy is computed once: a map holds few distinct values (sums of the hit and miss
/// log-odds, clamped), and the sum adds the same terms in the same order. Neighbours along k
/// mostly share a value (free space at the clamp), so the last value's entropy is kept at hand.
class MeasuredEntropy {
 public:
  void add(float log_odds) {
    if (const auto key = std::bit_cast<std::uint32_t>(log_odds); key != last_value_) {
      const auto [entry, added] = bits_of_value_.try_emplace(key);
      if (added) entry->second = kernels::entropyNats(grid::OccupancyMap::probabilityOf(log_odds)) / std::log(2.0);
      last_value_ = key;
      last_bits_ = entry->second;
    }
    bits_ += last_bits_;
    ++measured_;
  }
  double bits() const { return bits_; }
  std::size_t measured() const { return measured_; }

 private:
  std::unordered_map<std::uint32_t, double> bits_of_value_;
  std::uint32_t last_value_ = std::bit_cast<std::uint32_t>(std::numeric_limits<float>::quiet_NaN());
  double last_bits_ = 0.0;
  double bits_ = 0.0;
  std::size_t measured_ = 0;
};

/// Values read into memory at once by mapEntropyBits(): 16 MB, or one (j, k) slab if larger.
constexpr std::size_t kEntropyReadValues = std::size_t{1} << 22;

}  // namespace

double mapEntropyBits(const grid::OccupancyMap& map, const Eigen::Vector3d& centre_world, double edge_m) {
  const int n = voxelsPerSide(map, edge_m);
  const grid::Index3 first = map.worldToIndex(centre_world) - grid::Index3::Constant(n / 2);
  const Eigen::AlignedBox3i cube(first, first + grid::Index3::Constant(n - 1));
  // Only measured voxels add terms, and they lie inside the map's measured bounds: that part
  // of the cube is read as dense log-odds (NaN: unmeasured) in slabs of whole (j, k) planes and
  // summed in (i, j, k) order, the same additions in the same order as over the sorted measured
  // voxels, without the sort, and without a buffer the size of the cube.
  MeasuredEntropy sum;
  const std::optional<Eigen::AlignedBox3i> bounds = map.measuredBoundsIndex();
  const Eigen::AlignedBox3i box = bounds ? cube.intersection(*bounds) : Eigen::AlignedBox3i();
  if (!box.isEmpty()) {
    const grid::Index3 size = box.sizes() + grid::Index3::Ones();
    const std::size_t plane = static_cast<std::size_t>(size.y()) * static_cast<std::size_t>(size.z());
    const int planes_per_read = static_cast<int>(std::clamp<std::size_t>(kEntropyReadValues / plane, 1, size.x()));
    std::vector<float> log_odds(plane * static_cast<std::size_t>(planes_per_read));
    for (int i = box.min().x(); i <= box.max().x(); i += planes_per_read) {
      Eigen::AlignedBox3i slab = box;
      slab.max().x() = std::min(box.max().x(), i + planes_per_read - 1);
      slab.min().x() = i;
      const std::span<float> values(log_odds.data(), plane * static_cast<std::size_t>(slab.max().x() - i + 1));
      std::fill(values.begin(), values.end(), std::numeric_limits<float>::quiet_NaN());
      map.copyMeasuredLogOdds(slab, values);
      for (const float value : values) {
        if (!std::isnan(value)) sum.add(value);
      }
    }
  }
  return sum.bits() + (maxMapEntropyBits(map, edge_m) - static_cast<double>(sum.measured()));  // 1 bit per unmeasured voxel
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
