#include "nbv/grid/occupancy_map.hpp"

#include "nbv/fork_join.hpp"

#include "nbv/errors.hpp"
#include "vdb_grids.hpp"

#include <openvdb/tree/ValueAccessor.h>
#include <tbb/blocked_range.h>
#include <tbb/parallel_reduce.h>

#include <algorithm>
#include <bit>
#include <cmath>
#include <cstring>
#include <limits>
#include <mutex>
#include <sstream>

namespace nbv::grid {

using kernels::octomapNormalized;
using kernels::traverseRayKeys;

namespace {

/// `from + direction * length_m`, in single precision per component as OctoMap computes it.
Eigen::Vector3f pointAlong(const Eigen::Vector3f& from, const Eigen::Vector3f& direction, float length_m) {
  return {from.x() + direction.x() * length_m, from.y() + direction.y() * length_m,
          from.z() + direction.z() * length_m};
}

std::string formatPoint(const Eigen::Vector3f& p) {
  std::ostringstream out;
  out << '(' << p.x() << ", " << p.y() << ", " << p.z() << ')';
  return out.str();
}

/// What each point of a scan contributes, as OctoMap's computeUpdate decides it: a point
/// within max_range gives a ray to it and a hit; a point beyond gives a ray to origin +
/// direction * max_range and no hit; a point (or such an end) outside the index range gives
/// nothing. A point nearer than min_range (0 in OctoMap) gives nothing either.
class ScanRays {
 public:
  enum Kind : std::uint8_t { kSkipped, kHit, kBeyondRange, kTooNear };

  ScanRays(const Eigen::Vector3f& origin, const VoxelLattice& lattice, const MapConfig& config)
      : origin_(&origin), lattice_(&lattice), max_range_(config.max_range),
        max_norm_sq_(largestSquareWithin(config.max_range)),
        near_norm_sq_(config.min_range > 0.0 ? largestSquareBelow(config.min_range) : -1.0f) {}

  /// Whether a point of kind `k` adds a ray.
  static bool casts(Kind k) { return k == kHit || k == kBeyondRange; }

  Kind kind(const Eigen::Vector3f& p) const {
    if (!lattice_->inRange(p)) return kSkipped;
    const Eigen::Vector3f offset = p - *origin_;
    // octomapNorm(offset) <= max_range, without the square root.
    const float norm_sq = offset.x() * offset.x() + offset.y() * offset.y() + offset.z() * offset.z();
    if (norm_sq <= near_norm_sq_) return kTooNear;  // octomapNorm(offset) < min_range
    if (norm_sq <= max_norm_sq_) return kHit;
    return lattice_->inRange(beyondEnd(p)) ? kBeyondRange : kSkipped;
  }
  /// The end of the ray of a point beyond max_range.
  Eigen::Vector3f beyondEnd(const Eigen::Vector3f& p) const {
    return pointAlong(*origin_, octomapNormalized(p - *origin_), static_cast<float>(max_range_));
  }
  /// The end of the ray of a point of kind `k` (one that casts()).
  Eigen::Vector3f end(const Eigen::Vector3f& p, Kind k) const { return k == kHit ? p : beyondEnd(p); }

 private:
  /// The largest float s with sqrt(double(s)) <= limit, so that for every float s,
  /// s <= largestSquareWithin(limit) exactly when octomapNorm's sqrt(double(s)) <= limit (the
  /// correctly rounded square root is monotonic). limit: finite and > 0.
  static float largestSquareWithin(double limit) {
    const auto within = [limit](float s) { return std::sqrt(static_cast<double>(s)) <= limit; };
    float s = static_cast<float>(limit * limit);  // within an ulp or two of the answer
    while (s < std::numeric_limits<float>::infinity() && within(std::nextafter(s, std::numeric_limits<float>::infinity()))) {
      s = std::nextafter(s, std::numeric_limits<float>::infinity());
    }
    while (s > 0.0f && !within(s)) s = std::nextafter(s, 0.0f);
    return s;
  }
  /// The largest float s with sqrt(double(s)) < limit. limit: finite and > 0.
  static float largestSquareBelow(double limit) {
    const float s = largestSquareWithin(limit);
    return std::sqrt(static_cast<double>(s)) < limit ? s : std::nextafter(s, 0.0f);
  }

  const Eigen::Vector3f* origin_;
  const VoxelLattice* lattice_;
  double max_range_;
  float max_norm_sq_;
  float near_norm_sq_;  ///< the largest float square whose norm lies below min_range; -1: none
};

/// A set of voxels collected by one TBB task; tasks join by union, so the result does not
/// depend on how TBB splits the work.
struct VoxelSetBody {
  const std::vector<Eigen::Vector3f>* ends;
  const Eigen::Vector3f* origin;
  const VoxelLattice* lattice;
  openvdb::MaskTree crossed;

  VoxelSetBody(const std::vector<Eigen::Vector3f>& e, const Eigen::Vector3f& o, const VoxelLattice& l)
      : ends(&e), origin(&o), lattice(&l) {}
  VoxelSetBody(VoxelSetBody& other, tbb::split)
      : ends((ForkJoin::enter(), ForkJoin::observe(&other), other.ends)), origin(other.origin),
        lattice(other.lattice) {
    ForkJoin::publish(this);
  }

  void operator()(const tbb::blocked_range<std::size_t>& range) {
    ForkJoin::enter();
    openvdb::tree::ValueAccessor<openvdb::MaskTree> acc(crossed);
    for (std::size_t i = range.begin(); i != range.end(); ++i) {
      traverseRayKeys(*origin, (*ends)[i], *lattice,
                      [&acc](const Index3& ijk) { acc.setValueOn(toCoord(ijk)); });
    }
    ForkJoin::leave();
    ForkJoin::publish(this);
  }
  void join(VoxelSetBody& other) {
    ForkJoin::observe(&other);
    ForkJoin::joined();
    crossed.topologyUnion(other.crossed);
    ForkJoin::leave();
    ForkJoin::publish(this);
  }
};

/// Proximity candidates of one TBB task: the smallest step index per voxel along segments
/// starts[i] -> beyond[i] (the hit voxel, k = 0, excluded); join keeps minima. Whether a
/// candidate is measured is decided when marks are applied.
struct ProximityBody {
  const std::vector<Eigen::Vector3f>* starts;
  const std::vector<Eigen::Vector3f>* beyond;
  const VoxelLattice* lattice;
  openvdb::Int32Tree marks{0};

  ProximityBody(const std::vector<Eigen::Vector3f>& s, const std::vector<Eigen::Vector3f>& b, const VoxelLattice& l)
      : starts(&s), beyond(&b), lattice(&l) {}
  ProximityBody(ProximityBody& other, tbb::split)
      : starts((ForkJoin::enter(), ForkJoin::observe(&other), other.starts)),
        beyond(other.beyond), lattice(other.lattice) {
    ForkJoin::publish(this);
  }

  void operator()(const tbb::blocked_range<std::size_t>& range) {
    ForkJoin::enter();
    openvdb::tree::ValueAccessor<openvdb::Int32Tree> acc(marks);
    for (std::size_t i = range.begin(); i != range.end(); ++i) {
      std::int32_t k = 0;
      traverseRayKeys((*starts)[i], (*beyond)[i], *lattice, [&](const Index3& ijk) {
        const std::int32_t d = k++;
        if (d == 0) return;
        std::int32_t current;
        if (!acc.probeValue(toCoord(ijk), current) || d < current) acc.setValueOn(toCoord(ijk), d);
      });
    }
    ForkJoin::leave();
    ForkJoin::publish(this);
  }
  void join(ProximityBody& other) {
    ForkJoin::observe(&other);
    ForkJoin::joined();
    openvdb::tree::ValueAccessor<openvdb::Int32Tree> acc(marks);
    for (auto it = other.marks.cbeginValueOn(); it; ++it) {
      std::int32_t current;
      if (!acc.probeValue(it.getCoord(), current) || *it < current) acc.setValueOn(it.getCoord(), *it);
    }
    ForkJoin::leave();
    ForkJoin::publish(this);
  }
};

template <class Body>
void runReduce(std::size_t count, const IntegrateOptions& parallel, Body& body) {
  if (count == 0) return;
  if (parallel.serial) {
    body(tbb::blocked_range<std::size_t>(0, count));
  } else {
    ForkJoin::publish(&body);
    ForkJoin::fork();
    tbb::parallel_reduce(
        tbb::blocked_range<std::size_t>(0, count, std::max<std::size_t>(1, parallel.grain_size)),
        body);
    ForkJoin::joined();
    ForkJoin::observe(&body);
  }
}

/// Owns the bytes of an 8-aligned kernels::DenseBox spanning [lo, hi]. Zero-initialised.
/// Visits its contents leaf by leaf, in OpenVDB's 8^3 leaf blocks. Optionally a second plane
/// of the same layout flags end voxels (hits), which win over the first plane's value.
class DenseScratch {
 public:
  static constexpr std::uint8_t kCrossed = 1, kHit = 2;  ///< the occupancy states
  enum Planes { kValuesOnly = 1, kWithHits = 2 };

  DenseScratch(const Index3& lo, const Index3& hi) : box_(kernels::DenseBox::around(lo, hi)) {}
  std::uint64_t bytes() const { return box_.bytes(); }
  void allocate(Planes planes = kValuesOnly) {
    if (bytes() > static_cast<std::uint64_t>(std::numeric_limits<std::ptrdiff_t>::max()) / planes) throw std::bad_alloc();
    data_ = std::make_unique<std::uint8_t[]>(bytes() * planes);
    box_.data = data_.get();
    hits_ = planes == kWithHits ? data_.get() + bytes() : nullptr;
  }
  const kernels::DenseBox& box() const { return box_; }
  /// The plane of hit flags (allocated kWithHits only), in the box's layout.
  std::uint8_t* hits() const { return hits_; }

  /// Calls visit(leaf_origin, n, byte) for every non-zero byte (kHit where the hit plane is
  /// set), n being the voxel's offset in its OpenVDB leaf; leaf by leaf, so callers fetch each
  /// leaf once. Skips empty rows.
  template <class Visit>
  void forEachSet(Visit&& visit) const {
    const std::size_t sx = box_.size[0], sy = box_.size[1];
    for (std::uint32_t z0 = 0; z0 < box_.size[2]; z0 += 8) {
      for (std::uint32_t y0 = 0; y0 < box_.size[1]; y0 += 8) {
        for (std::uint32_t x0 = 0; x0 < box_.size[0]; x0 += 8) {
          const openvdb::Coord origin(box_.min[0] + static_cast<int>(x0), box_.min[1] + static_cast<int>(y0),
                                      box_.min[2] + static_cast<int>(z0));
          for (unsigned dz = 0; dz < 8; ++dz) {
            for (unsigned dy = 0; dy < 8; ++dy) {
              const std::size_t row = ((z0 + dz) * sy + (y0 + dy)) * sx + x0;
              std::uint64_t word, hit_word = 0;
              std::memcpy(&word, data_.get() + row, 8);
              if (hits_ != nullptr) std::memcpy(&hit_word, hits_ + row, 8);
              if ((word | hit_word) == 0) continue;
              for (unsigned dx = 0; dx < 8; ++dx) {
                const std::uint8_t value = hits_ != nullptr && hits_[row + dx] != 0 ? kHit : data_[row + dx];
                if (value != 0) visit(origin, static_cast<openvdb::Index>((dx << 6) | (dy << 3) | dz), value);
              }
            }
          }
        }
      }
    }
  }

 private:
  kernels::DenseBox box_;
  std::unique_ptr<std::uint8_t[]> data_;
  std::uint8_t* hits_ = nullptr;
};

/// Runs `body(range)` over [0, count): on the calling thread if serial, else with TBB.
template <class Body>
void runFor(std::size_t count, const IntegrateOptions& options, const Body& body) {
  if (count == 0) return;
  if (options.serial) {
    body(tbb::blocked_range<std::size_t>(0, count));
  } else {
    // Fixed chunks of grain_size, handed out by index (TBB reads the index, nbv builds the range).
    const std::size_t grain = std::max<std::size_t>(1, options.grain_size);
    const auto chunk_task = [&](std::size_t chunk) {
      body(tbb::blocked_range<std::size_t>(chunk * grain, std::min(count, (chunk + 1) * grain)));
    };
    ForkJoin::parallelFor((count + grain - 1) / grain, chunk_task);
  }
}

/// Voxels that fell outside a scratch box (rare: rounding at a ray's end); applied serially.
template <class T>
class Overflow {
 public:
  void push(const T& item) {
    std::lock_guard<std::mutex> lock(mutex_);
    items_.push_back(item);
  }
  std::vector<T>& items() { return items_; }

 private:
  std::mutex mutex_;
  std::vector<T> items_;
};

}  // namespace

// Pass 1 over the points: their kinds, the counts and the boxes of the rays and of the hits.
// Only a byte per point is kept, not a second list of points.
struct ScanUpdate::Classified {
  std::vector<ScanRays::Kind> kinds;
  Index3 ray_min, ray_max;          ///< the voxels of every ray's end and of the origin lie within
  Eigen::Vector3f hit_min, hit_max;  ///< world bounds of the hit points
};

namespace {

/// OctoMap's computeDiscreteUpdate: one point per distinct voxel of the points, in the order
/// of first appearance, at the voxel's centre as OctoMap's keyToCoord gives it (double, then
/// float). Points that are not finite or out of the index range are left out (OctoMap's
/// unchecked coordToKey would wrap them) and counted in `left_out`. Distinct voxels are found
/// with one byte per voxel of the points' box when it fits `max_scratch_bytes`, else by sorting.
std::vector<Eigen::Vector3f> discretized(std::span<const Eigen::Vector3f> points, const VoxelLattice& lattice,
                                         std::size_t max_scratch_bytes, std::size_t& left_out) {
  std::vector<Index3> voxels;  // of the points in range, in order
  voxels.reserve(points.size());
  Index3 lo = Index3::Constant(std::numeric_limits<int>::max()), hi = Index3::Constant(std::numeric_limits<int>::min());
  for (const Eigen::Vector3f& p : points) {
    if (!lattice.inRange(p)) continue;
    const Index3& ijk = voxels.emplace_back(lattice.worldToIndex(p));
    lo = lo.cwiseMin(ijk);
    hi = hi.cwiseMax(ijk);
  }
  left_out = points.size() - voxels.size();
  std::vector<Eigen::Vector3f> centres;
  if (voxels.empty()) return centres;
  auto centre = [&](const Index3& ijk) {
    return Eigen::Vector3f(static_cast<float>(lattice.indexToWorld(ijk.x())), static_cast<float>(lattice.indexToWorld(ijk.y())),
                           static_cast<float>(lattice.indexToWorld(ijk.z())));
  };
  const Eigen::Array<std::uint64_t, 3, 1> size = (hi - lo).cast<std::int64_t>().array().cast<std::uint64_t>() + 1;
  if (size.prod() <= max_scratch_bytes) {
    std::vector<std::uint8_t> seen(size.prod(), 0);
    for (const Index3& ijk : voxels) {
      const Eigen::Array<std::uint64_t, 3, 1> at = (ijk - lo).cast<std::int64_t>().array().cast<std::uint64_t>();
      std::uint8_t& flag = seen[(at.z() * size.y() + at.y()) * size.x() + at.x()];
      if (flag == 0) centres.push_back(centre(ijk));
      flag = 1;
    }
    return centres;
  }
  std::vector<std::pair<Index3, std::uint32_t>> keyed;  // (voxel, first appearance)
  keyed.reserve(voxels.size());
  for (std::size_t i = 0; i < voxels.size(); ++i) keyed.emplace_back(voxels[i], static_cast<std::uint32_t>(i));
  std::stable_sort(keyed.begin(), keyed.end(), [](const auto& a, const auto& b) { return lessIjk(a.first, b.first); });
  keyed.erase(std::unique(keyed.begin(), keyed.end(), [](const auto& a, const auto& b) { return a.first == b.first; }), keyed.end());
  std::sort(keyed.begin(), keyed.end(), [](const auto& a, const auto& b) { return a.second < b.second; });
  for (const auto& [ijk, first] : keyed) centres.push_back(centre(ijk));
  return centres;
}

}  // namespace

ScanUpdate::ScanUpdate(const MapConfig& config, std::span<const Eigen::Vector3f> points_world,
                       const Eigen::Vector3f& origin_world, const IntegrateOptions& options)
    : config_((config.validate(), config)), lattice_(config.resolution), origin_(origin_world) {
  if (!lattice_.inRange(origin_world)) {
    throw InvalidArgument("sensor origin " + formatPoint(origin_world) +
                          " is not finite or outside the map's index range");
  }
  std::vector<Eigen::Vector3f> centres;
  const std::size_t given = points_world.size();
  std::size_t left_out = 0;
  if (options.discretize) points_world = centres = discretized(points_world, lattice_, options.max_scratch_bytes, left_out);
  const Classified scan = classify(points_world);
  if (options.discretize) {  // the counts of the points given; hits and beyond_range count the rays
    points_.points = given;
    points_.skipped_points += left_out;
  }
  markOccupancy(points_world, scan, options);
  if (config_.proximity_range > 0.0 && points_.hits > 0) markProximity(points_world, scan, options);
}

ScanUpdate::Classified ScanUpdate::classify(std::span<const Eigen::Vector3f> points_world) {
  const ScanRays rays(origin_, lattice_, config_);
  Classified scan;
  scan.kinds.resize(points_world.size());
  points_.points = points_world.size();
  // World-space bounds; floor is monotonic, so their voxels bound every end voxel.
  Eigen::Vector3f end_min = origin_, end_max = origin_;
  scan.hit_min.setConstant(std::numeric_limits<float>::max());
  scan.hit_max.setConstant(std::numeric_limits<float>::lowest());
  for (std::size_t i = 0; i < points_world.size(); ++i) {
    const Eigen::Vector3f& p = points_world[i];
    const ScanRays::Kind kind = scan.kinds[i] = rays.kind(p);
    if (!ScanRays::casts(kind)) {
      ++(kind == ScanRays::kTooNear ? points_.too_near : points_.skipped_points);
      continue;
    }
    const Eigen::Vector3f end = kind == ScanRays::kHit ? p : rays.beyondEnd(p);
    end_min = end_min.cwiseMin(end);
    end_max = end_max.cwiseMax(end);
    if (kind == ScanRays::kBeyondRange) {
      ++points_.beyond_range;
      continue;
    }
    ++points_.hits;
    scan.hit_min = scan.hit_min.cwiseMin(p);
    scan.hit_max = scan.hit_max.cwiseMax(p);
  }
  scan.ray_min = lattice_.worldToIndex(end_min);
  scan.ray_max = lattice_.worldToIndex(end_max);
  return scan;
}

void ScanUpdate::markOccupancy(std::span<const Eigen::Vector3f> points_world, const Classified& scan,
                               const IntegrateOptions& options) {
  // Each voxel is updated once: a hit if it is an end voxel, else a miss. Dense scratch over the
  // rays' box (padded by one voxel for rounding at the ends) when it fits the budget, else
  // sparse voxel sets.
  const ScanRays rays(origin_, lattice_, config_);
  const kernels::Isa isa = options.isa.value_or(kernels::bestIsa());
  DenseScratch scratch(scan.ray_min - Index3::Ones(), scan.ray_max + Index3::Ones());
  if (scratch.bytes() <= options.max_scratch_bytes) {
    scratch.allocate(DenseScratch::kWithHits);
    Overflow<Index3> outside;
    const kernels::OutsideSink to_outside = [&outside](const Index3& ijk, std::uint8_t) { outside.push(ijk); };
    const kernels::MarkSpec crossed{kernels::MarkSpec::Mode::Store, DenseScratch::kCrossed};
    kernels::MarkSpec crossed_and_hit = crossed;  // hits flag their end voxels too
    crossed_and_hit.end_flags = scratch.hits();
    runFor(points_world.size(), options, [&](const tbb::blocked_range<std::size_t>& range) {
      // The rays' ends, a block at a time, hits apart; end voxels go to their own plane, so
      // no crossing written later can overwrite them.
      std::array<Eigen::Vector3f, 256> ends[2];  // hits, beyond max_range
      std::size_t count[2] = {0, 0};
      auto mark = [&](int set) {
        kernels::markRays(std::span(&origin_, 1), std::span(ends[set].data(), count[set]), lattice_,
                          scratch.box(), set == 0 ? crossed_and_hit : crossed, to_outside, isa);
        count[set] = 0;
      };
      for (std::size_t i = range.begin(); i != range.end(); ++i) {
        if (!ScanRays::casts(scan.kinds[i])) continue;
        const int set = scan.kinds[i] == ScanRays::kHit ? 0 : 1;
        ends[set][count[set]] = rays.end(points_world[i], scan.kinds[i]);
        if (++count[set] == ends[set].size()) mark(set);
      }
      mark(0);
      mark(1);
    });
    scratch.forEachSet([&](const openvdb::Coord& origin, openvdb::Index n, std::uint8_t state) {
      if (occupancy_.empty() || occupancy_.back().origin != toIndex(origin)) occupancy_.push_back({toIndex(origin)});
      setBit(state == DenseScratch::kHit ? occupancy_.back().hit : occupancy_.back().crossed, n);
    });
    // Crossed voxels outside the box cannot be end voxels (those are all inside): misses.
    misses_outside_ = std::move(outside.items());
    std::sort(misses_outside_.begin(), misses_outside_.end(), lessIjk);
    misses_outside_.erase(std::unique(misses_outside_.begin(), misses_outside_.end()), misses_outside_.end());
    return;
  }
  std::vector<Eigen::Vector3f> ends;  // of every free-space segment
  ends.reserve(points_world.size() - points_.skipped_points);
  openvdb::MaskTree hit_set;
  openvdb::tree::ValueAccessor<openvdb::MaskTree> hit_acc(hit_set);
  for (std::size_t i = 0; i < points_world.size(); ++i) {
    if (!ScanRays::casts(scan.kinds[i])) continue;
    ends.push_back(rays.end(points_world[i], scan.kinds[i]));
    if (scan.kinds[i] == ScanRays::kHit) hit_acc.setValueOn(toCoord(lattice_.worldToIndex(ends.back())));
  }
  VoxelSetBody crossed(ends, origin_, lattice_);
  runReduce(ends.size(), options, crossed);
  openvdb::MaskTree touched(crossed.crossed);
  touched.topologyUnion(hit_set);
  openvdb::tree::ValueAccessor<const openvdb::MaskTree> crossed_acc(crossed.crossed);
  for (auto leaf = touched.cbeginLeaf(); leaf; ++leaf) {
    OccupancyBlock& block = occupancy_.emplace_back(OccupancyBlock{toIndex(leaf->origin())});
    const auto* crossed_leaf = crossed_acc.probeConstLeaf(leaf->origin());
    const auto* hit_leaf = hit_acc.probeConstLeaf(leaf->origin());
    for (auto on = leaf->getValueMask().beginOn(); on; ++on) {
      if (hit_leaf != nullptr && hit_leaf->isValueOn(on.pos())) {
        setBit(block.hit, on.pos());  // the hit wins
      } else if (crossed_leaf != nullptr && crossed_leaf->isValueOn(on.pos())) {
        setBit(block.crossed, on.pos());
      }
    }
  }
}

void ScanUpdate::markProximity(std::span<const Eigen::Vector3f> points_world, const Classified& scan,
                               const IntegrateOptions& options) {
  // Each hit ray continued beyond its hit point for proximity_range; the k-th voxel after the
  // hit voxel (k >= 1) is a candidate at distance k, the smallest kept.
  const auto range_f = static_cast<float>(config_.proximity_range);
  // Point i's continuation, from the hit to `end`, proximity_range beyond it: none for a point
  // that is no hit or whose end lies out of the index range.
  const auto continuation = [&](std::size_t i, Eigen::Vector3f& end) {
    if (scan.kinds[i] != ScanRays::kHit) return false;
    const Eigen::Vector3f& p = points_world[i];
    end = pointAlong(p, octomapNormalized(p - origin_), range_f);
    return lattice_.inRange(end);
  };
  // A ray of length L crosses at most 3 L / resolution + 3 voxels: distances fit a byte when
  // that is below 256.
  const double reach_voxels = std::ceil(config_.proximity_range / config_.resolution) + 2.0;
  DenseScratch marks(lattice_.worldToIndex(scan.hit_min) - Index3::Constant(static_cast<int>(reach_voxels)),
                     lattice_.worldToIndex(scan.hit_max) + Index3::Constant(static_cast<int>(reach_voxels)));
  if (3.0 * reach_voxels + 3.0 < 256.0 && reach_voxels < 1e6 && marks.bytes() <= options.max_scratch_bytes) {
    marks.allocate();
    Overflow<ProximityMark> outside;
    const kernels::OutsideSink to_outside = [&outside](const Index3& ijk, std::uint8_t d) {
      outside.push({ijk, d});
    };
    const kernels::MarkSpec nearest{kernels::MarkSpec::Mode::MinStepIndex, 0};
    const kernels::Isa isa = options.isa.value_or(kernels::bestIsa());
    // The continuations a block at a time, made in the tasks that walk them (no scan-sized
    // arrays: their fresh pages cost more than the walk they feed).
    runFor(points_world.size(), options, [&](const tbb::blocked_range<std::size_t>& range) {
      std::array<Eigen::Vector3f, 256> from, to;
      std::size_t count = 0;
      const auto mark = [&] {
        kernels::markRays(std::span(from.data(), count), std::span(to.data(), count), lattice_, marks.box(), nearest,
                          to_outside, isa);
        count = 0;
      };
      for (std::size_t i = range.begin(); i != range.end(); ++i) {
        if (!continuation(i, to[count])) continue;
        from[count] = points_world[i];
        if (++count == from.size()) mark();
      }
      mark();
    });
    // forEachSet() visits a block's voxels in the order of its rows, not of the bits: each
    // block's distances are kept by offset until the next block starts, then listed in bit order.
    std::array<std::uint8_t, 512> block_distances{};
    const auto list_distances = [&] {
      if (marks_.empty()) return;
      forEachBit(marks_.back().marked, [&](openvdb::Index n) { distances_.push_back(block_distances[n]); });
    };
    marks.forEachSet([&](const openvdb::Coord& origin, openvdb::Index n, std::uint8_t d) {
      if (marks_.empty() || marks_.back().origin != toIndex(origin)) {
        list_distances();
        marks_.push_back({toIndex(origin), {}, distances_.size()});
      }
      setBit(marks_.back().marked, n);
      block_distances[n] = d;
    });
    list_distances();
    marks_outside_ = std::move(outside.items());
    return;
  }
  std::vector<Eigen::Vector3f> starts, beyond;
  for (std::size_t i = 0; i < points_world.size(); ++i) {
    Eigen::Vector3f end;
    if (!continuation(i, end)) continue;
    starts.push_back(points_world[i]);
    beyond.push_back(end);
  }
  ProximityBody candidates(starts, beyond, lattice_);
  runReduce(starts.size(), options, candidates);
  for (auto it = candidates.marks.cbeginValueOn(); it; ++it) marks_outside_.push_back({toIndex(it.getCoord()), *it});
}

std::size_t ScanUpdate::voxelCount() const {
  std::size_t count = misses_outside_.size();
  for (const OccupancyBlock& block : occupancy_) {
    for (int w = 0; w < 8; ++w) count += static_cast<std::size_t>(std::popcount(block.crossed[w] | block.hit[w]));
  }
  return count;
}

}  // namespace nbv::grid
