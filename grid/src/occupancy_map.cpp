#include "nbv/grid/occupancy_map.hpp"

#include "nbv/kernels/fork_join.hpp"

#include "nbv/errors.hpp"
#include "nbv/kernels/information_gain.hpp"
#include "vdb_grids.hpp"

#include <openvdb/tree/ValueAccessor.h>
#include <tbb/blocked_range.h>
#include <tbb/parallel_reduce.h>

#include <algorithm>
#include <array>
#include <atomic>
#include <cstring>
#include <functional>
#include <limits>
#include <cmath>
#include <mutex>
#include <sstream>

namespace nbv::grid {

using kernels::octomapNormalized;
using kernels::octomapNorm;
using kernels::traverseRayKeys;

namespace {

/// Orders voxel indices by (i, j, k).
bool lessIjk(const Index3& a, const Index3& b) {
  return std::lexicographical_compare(a.data(), a.data() + 3, b.data(), b.data() + 3);
}

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
/// nothing.
class ScanRays {
 public:
  enum Kind : std::uint8_t { kSkipped, kHit, kBeyondRange };

  ScanRays(const Eigen::Vector3f& origin, const VoxelLattice& lattice, double max_range)
      : origin_(&origin), lattice_(&lattice), max_range_(max_range),
        max_norm_sq_(largestSquareWithin(max_range)) {}

  Kind kind(const Eigen::Vector3f& p) const {
    if (!lattice_->inRange(p)) return kSkipped;
    const Eigen::Vector3f offset = p - *origin_;
    // octomapNorm(offset) <= max_range, without the square root.
    const float norm_sq = offset.x() * offset.x() + offset.y() * offset.y() + offset.z() * offset.z();
    if (norm_sq <= max_norm_sq_) return kHit;
    return lattice_->inRange(beyondEnd(p)) ? kBeyondRange : kSkipped;
  }
  /// The end of the ray of a point beyond max_range.
  Eigen::Vector3f beyondEnd(const Eigen::Vector3f& p) const {
    return pointAlong(*origin_, octomapNormalized(p - *origin_), static_cast<float>(max_range_));
  }
  /// The end of the ray of a point of kind `k` (not kSkipped).
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

  const Eigen::Vector3f* origin_;
  const VoxelLattice* lattice_;
  double max_range_;
  float max_norm_sq_;
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
      : ends((kernels::ForkJoin::enter(), kernels::ForkJoin::observe(&other), other.ends)), origin(other.origin),
        lattice(other.lattice) {
    kernels::ForkJoin::publish(this);
  }

  void operator()(const tbb::blocked_range<std::size_t>& range) {
    kernels::ForkJoin::enter();
    openvdb::tree::ValueAccessor<openvdb::MaskTree> acc(crossed);
    for (std::size_t i = range.begin(); i != range.end(); ++i) {
      traverseRayKeys(*origin, (*ends)[i], *lattice,
                      [&acc](const Index3& ijk) { acc.setValueOn(toCoord(ijk)); });
    }
    kernels::ForkJoin::leave();
    kernels::ForkJoin::publish(this);
  }
  void join(VoxelSetBody& other) {
    kernels::ForkJoin::observe(&other);
    kernels::ForkJoin::joined();
    crossed.topologyUnion(other.crossed);
    kernels::ForkJoin::leave();
    kernels::ForkJoin::publish(this);
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
      : starts((kernels::ForkJoin::enter(), kernels::ForkJoin::observe(&other), other.starts)),
        beyond(other.beyond), lattice(other.lattice) {
    kernels::ForkJoin::publish(this);
  }

  void operator()(const tbb::blocked_range<std::size_t>& range) {
    kernels::ForkJoin::enter();
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
    kernels::ForkJoin::leave();
    kernels::ForkJoin::publish(this);
  }
  void join(ProximityBody& other) {
    kernels::ForkJoin::observe(&other);
    kernels::ForkJoin::joined();
    openvdb::tree::ValueAccessor<openvdb::Int32Tree> acc(marks);
    for (auto it = other.marks.cbeginValueOn(); it; ++it) {
      std::int32_t current;
      if (!acc.probeValue(it.getCoord(), current) || *it < current) acc.setValueOn(it.getCoord(), *it);
    }
    kernels::ForkJoin::leave();
    kernels::ForkJoin::publish(this);
  }
};

template <class Body>
void runReduce(std::size_t count, const IntegrateOptions& parallel, Body& body) {
  if (count == 0) return;
  if (parallel.serial) {
    body(tbb::blocked_range<std::size_t>(0, count));
  } else {
    kernels::ForkJoin::publish(&body);
    kernels::ForkJoin::fork();
    tbb::parallel_reduce(
        tbb::blocked_range<std::size_t>(0, count, std::max<std::size_t>(1, parallel.grain_size)),
        body);
    kernels::ForkJoin::joined();
    kernels::ForkJoin::observe(&body);
  }
}

}  // namespace

openvdb::math::Transform::Ptr makeTransform(double resolution) {
  auto transform = openvdb::math::Transform::createLinearTransform(resolution);
  transform->postTranslate(openvdb::Vec3d(0.5 * resolution));
  return transform;
}

void initializeOpenVdb() {
  static std::once_flag once;
  std::call_once(once, [] { openvdb::initialize(); });
}

void MapConfig::validate() const {
  auto require = [](bool ok, const char* name, double value, const char* rule) {
    if (!ok) {
      std::ostringstream out;
      out << "invalid map configuration: " << name << " = " << value << " (" << rule << ')';
      throw InvalidArgument(out.str());
    }
  };
  auto open_unit = [](double p) { return std::isfinite(p) && p > 0.0 && p < 1.0; };
  require(std::isfinite(resolution) && resolution > 0.0, "resolution", resolution,
          "must be finite and > 0");
  require(open_unit(p_hit) && p_hit > 0.5, "p_hit", p_hit, "must be in (0.5, 1)");
  require(open_unit(p_miss) && p_miss < 0.5, "p_miss", p_miss, "must be in (0, 0.5)");
  require(open_unit(clamp_min) && clamp_min < 0.5, "clamp_min", clamp_min, "must be in (0, 0.5)");
  require(open_unit(clamp_max) && clamp_max > 0.5, "clamp_max", clamp_max, "must be in (0.5, 1)");
  require(std::isfinite(max_range) && max_range > 0.0, "max_range", max_range,
          "must be finite and > 0");
  require(std::isfinite(proximity_range) && proximity_range >= 0.0, "proximity_range",
          proximity_range, "must be finite and >= 0");
  require(open_unit(occupied_threshold), "occupied_threshold", occupied_threshold,
          "must be in (0, 1)");
  require(open_unit(free_threshold) && free_threshold <= occupied_threshold, "free_threshold",
          free_threshold, "must be in (0, 1) and <= occupied_threshold");
}

double OccupancyMap::probabilityOf(float log_odds) {
  return kernels::occupancyProbability(log_odds);
}

float OccupancyMap::logOddsOf(double probability) {
  return static_cast<float>(std::log(probability / (1.0 - probability)));
}

namespace {

/// Revisions come from one process-wide counter, so no two maps share one.
std::uint64_t nextRevision() {
  static std::atomic<std::uint64_t> counter{0};
  return ++counter;
}

/// The change log keeps at most this many block records; older history is dropped.
constexpr std::size_t kMaxChangeLog = std::size_t{1} << 20;

}  // namespace

OccupancyMap::OccupancyMap(const Config& config)
    : config_(config), lattice_(config.resolution), grids_(std::make_unique<Grids>()),
      revision_(nextRevision()), history_start_(revision_) {
  config_.validate();
  const auto transform = makeTransform(config_.resolution);
  grids_->log_odds = openvdb::FloatGrid::create(0.0f);
  grids_->log_odds->setTransform(transform);
  grids_->log_odds->setName("occupancy_log_odds");
  grids_->proximity = openvdb::Int32Grid::create(0);
  grids_->proximity->setTransform(transform->copy());
  grids_->proximity->setName("proximity");
}

OccupancyMap::~OccupancyMap() = default;
OccupancyMap::OccupancyMap(OccupancyMap&&) noexcept = default;
OccupancyMap& OccupancyMap::operator=(OccupancyMap&&) noexcept = default;

OccupancyMap::OccupancyMap(const OccupancyMap& other)
    : config_(other.config_), lattice_(other.lattice_), grids_(std::make_unique<Grids>()),
      revision_(other.revision_), history_start_(other.history_start_), change_log_(other.change_log_) {
  grids_->log_odds = other.grids_->log_odds->deepCopy();
  grids_->proximity = other.grids_->proximity->deepCopy();
}

OccupancyMap& OccupancyMap::operator=(const OccupancyMap& other) {
  if (this != &other) *this = OccupancyMap(other);
  return *this;
}

namespace {

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
    kernels::ForkJoin::parallelFor((count + grain - 1) / grain, chunk_task);
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

/// One voxel's occupancy update, as OctoMap's updateNodeLogOdds: add in single precision,
/// then clamp. Also removes the voxel's proximity mark (measured voxels are never marked).
struct VoxelUpdater {
  float hit_log, miss_log, min_log, max_log;

  void apply(openvdb::FloatTree::LeafNodeType& leaf, openvdb::Int32Tree::LeafNodeType* prox_leaf,
             openvdb::Index n, bool is_hit) const {
    const float current = leaf.isValueOn(n) ? leaf.getValue(n) : 0.0f;
    float value = current + (is_hit ? hit_log : miss_log);
    if (value < min_log) {
      value = min_log;
    } else if (value > max_log) {
      value = max_log;
    }
    leaf.setValueOn(n, value);
    if (prox_leaf != nullptr && prox_leaf->isValueOn(n)) prox_leaf->setValueOff(n, 0);
  }
};

/// Sets or lowers the proximity mark of one voxel unless it is measured; true if it changed.
bool applyMark(openvdb::tree::ValueAccessor<openvdb::Int32Tree>& prox_acc,
               openvdb::tree::ValueAccessor<const openvdb::FloatTree>& measured_acc,
               const openvdb::Coord& xyz, std::int32_t d) {
  if (measured_acc.isValueOn(xyz)) return false;
  std::int32_t current;
  if (prox_acc.probeValue(xyz, current) && current <= d) return false;
  prox_acc.setValueOn(xyz, d);
  return true;
}

openvdb::Index leafOffset(const Index3& ijk) {
  return static_cast<openvdb::Index>(((ijk.x() & 7) << 6) | ((ijk.y() & 7) << 3) | (ijk.z() & 7));
}

}  // namespace

ScanStats OccupancyMap::integrate(std::span<const Eigen::Vector3f> points_world,
                                  const Eigen::Vector3f& origin_world,
                                  const IntegrateOptions& options) {
  if (!lattice_.inRange(origin_world)) {
    throw InvalidArgument("sensor origin " + formatPoint(origin_world) +
                          " is not finite or outside the map's index range");
  }
  ScanStats stats;
  stats.points = points_world.size();
  beginChange();
  // Checked after the rays are marked in scratch sets and before the map is touched.
  auto refuseAboveCap = [this](std::size_t added, std::size_t cap) {
    const std::size_t total = measuredCount() + added;
    if (total > cap) {
      throw CapacityError("the scan would leave " + std::to_string(total) + " measured voxels, above the cap of " +
                          std::to_string(cap) + " (IntegrateOptions::max_measured_voxels)");
    }
  };

  // Pass 1 over the points: their kinds, the counts and the rays' box. Only a byte per point
  // is kept: scan-sized lists of points were refaulted from the kernel at every call (~20% of
  // the time of a full scan).
  const ScanRays rays(origin_world, lattice_, config_.max_range);
  std::vector<ScanRays::Kind> kinds(points_world.size());
  // World-space bounds; floor is monotonic, so their voxels bound every end voxel.
  float end_min[3], end_max[3];
  float hit_min[3] = {std::numeric_limits<float>::max(), std::numeric_limits<float>::max(),
                      std::numeric_limits<float>::max()};
  float hit_max[3] = {std::numeric_limits<float>::lowest(), std::numeric_limits<float>::lowest(),
                      std::numeric_limits<float>::lowest()};
  for (int a = 0; a < 3; ++a) end_min[a] = end_max[a] = origin_world[a];
  for (std::size_t i = 0; i < points_world.size(); ++i) {
    const Eigen::Vector3f& p = points_world[i];
    const ScanRays::Kind kind = kinds[i] = rays.kind(p);
    if (kind == ScanRays::kSkipped) {
      ++stats.skipped_points;
      continue;
    }
    const Eigen::Vector3f end = kind == ScanRays::kHit ? p : rays.beyondEnd(p);
    for (int a = 0; a < 3; ++a) {
      end_min[a] = std::min(end_min[a], end[a]);
      end_max[a] = std::max(end_max[a], end[a]);
    }
    if (kind == ScanRays::kBeyondRange) {
      ++stats.beyond_range;
      continue;
    }
    ++stats.hits;
    for (int a = 0; a < 3; ++a) {
      hit_min[a] = std::min(hit_min[a], p[a]);
      hit_max[a] = std::max(hit_max[a], p[a]);
    }
  }
  const Eigen::Vector3f hit_min_m(hit_min[0], hit_min[1], hit_min[2]);
  const Eigen::Vector3f hit_max_m(hit_max[0], hit_max[1], hit_max[2]);
  const Index3 ray_min = lattice_.worldToIndex(Eigen::Vector3f(end_min[0], end_min[1], end_min[2]));
  const Index3 ray_max = lattice_.worldToIndex(Eigen::Vector3f(end_max[0], end_max[1], end_max[2]));

  const VoxelUpdater updater{logOddsOf(config_.p_hit), logOddsOf(config_.p_miss),
                             logOddsOf(config_.clamp_min), logOddsOf(config_.clamp_max)};
  openvdb::tree::ValueAccessor<openvdb::FloatTree> log_acc(grids_->log_odds->tree());
  openvdb::tree::ValueAccessor<openvdb::Int32Tree> prox_acc(grids_->proximity->tree());
  const kernels::Isa isa = options.isa.value_or(kernels::bestIsa());

  // --- occupancy: each voxel updated once, a hit if it is an end voxel, else a miss --------
  // Dense scratch over the rays' box (padded by one voxel for rounding at the ends) when it
  // fits the budget, else sparse voxel sets.
  DenseScratch scratch(ray_min - Index3::Ones(), ray_max + Index3::Ones());
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
        kernels::markRays(std::span(&origin_world, 1), std::span(ends[set].data(), count[set]), lattice_,
                          scratch.box(), set == 0 ? crossed_and_hit : crossed, to_outside, isa);
        count[set] = 0;
      };
      for (std::size_t i = range.begin(); i != range.end(); ++i) {
        if (kinds[i] == ScanRays::kSkipped) continue;
        const int set = kinds[i] == ScanRays::kHit ? 0 : 1;
        ends[set][count[set]] = rays.end(points_world[i], kinds[i]);
        if (++count[set] == ends[set].size()) mark(set);
      }
      mark(0);
      mark(1);
    });
    // Crossed voxels outside the box cannot be end voxels (those are all inside): misses.
    auto& extra = outside.items();
    std::sort(extra.begin(), extra.end(), lessIjk);
    extra.erase(std::unique(extra.begin(), extra.end()), extra.end());
    if (options.max_measured_voxels > 0 && measuredCount() + scratch.bytes() + extra.size() > options.max_measured_voxels) {
      std::size_t added = 0;  // near the cap: count the voxels this scan would add
      scratch.forEachSet([&](const openvdb::Coord& origin, openvdb::Index n, std::uint8_t) {
        const auto* measured = log_acc.probeConstLeaf(origin);
        added += measured == nullptr || !measured->isValueOn(n);
      });
      for (const Index3& ijk : extra) added += !log_acc.isValueOn(toCoord(ijk));
      refuseAboveCap(added, options.max_measured_voxels);
    }
    openvdb::Coord leaf_origin(std::numeric_limits<int>::max());
    openvdb::FloatTree::LeafNodeType* leaf = nullptr;
    openvdb::Int32Tree::LeafNodeType* prox_leaf = nullptr;
    scratch.forEachSet([&](const openvdb::Coord& origin, openvdb::Index n, std::uint8_t state) {
      if (origin != leaf_origin) {
        leaf_origin = origin;
        noteChanged(toIndex(origin));
        leaf = log_acc.touchLeaf(origin);
        prox_leaf = prox_acc.probeLeaf(origin);
      }
      const bool is_hit = state == DenseScratch::kHit;
      updater.apply(*leaf, prox_leaf, n, is_hit);
      ++(is_hit ? stats.voxels_hit : stats.voxels_missed);
    });
    for (const Index3& ijk : extra) {
      noteChanged(ijk);
      const openvdb::Coord xyz = toCoord(ijk);
      updater.apply(*log_acc.touchLeaf(xyz), prox_acc.probeLeaf(xyz), leafOffset(ijk), false);
      ++stats.voxels_missed;
    }
  } else {
    std::vector<Eigen::Vector3f> ends;  // of every free-space segment
    ends.reserve(points_world.size() - stats.skipped_points);
    openvdb::MaskTree hit_set;
    openvdb::tree::ValueAccessor<openvdb::MaskTree> hit_acc(hit_set);
    for (std::size_t i = 0; i < points_world.size(); ++i) {
      if (kinds[i] == ScanRays::kSkipped) continue;
      ends.push_back(rays.end(points_world[i], kinds[i]));
      if (kinds[i] == ScanRays::kHit) hit_acc.setValueOn(toCoord(lattice_.worldToIndex(ends.back())));
    }
    VoxelSetBody crossed(ends, origin_world, lattice_);
    runReduce(ends.size(), options, crossed);
    if (options.max_measured_voxels > 0) {
      openvdb::MaskTree added(crossed.crossed);
      added.topologyUnion(hit_set);
      added.topologyDifference(grids_->log_odds->tree());
      refuseAboveCap(added.activeVoxelCount(), options.max_measured_voxels);
    }
    for (auto set_leaf = crossed.crossed.cbeginLeaf(); set_leaf; ++set_leaf) {
      const openvdb::Coord origin = set_leaf->origin();
      noteChanged(toIndex(origin));
      auto* leaf = log_acc.touchLeaf(origin);
      auto* prox_leaf = prox_acc.probeLeaf(origin);
      const auto* hit_leaf = hit_acc.probeConstLeaf(origin);
      for (auto on = set_leaf->getValueMask().beginOn(); on; ++on) {
        if (hit_leaf != nullptr && hit_leaf->isValueOn(on.pos())) continue;  // the hit wins
        updater.apply(*leaf, prox_leaf, on.pos(), false);
        ++stats.voxels_missed;
      }
    }
    for (auto set_leaf = hit_set.cbeginLeaf(); set_leaf; ++set_leaf) {
      noteChanged(toIndex(set_leaf->origin()));
      auto* leaf = log_acc.touchLeaf(set_leaf->origin());
      auto* prox_leaf = prox_acc.probeLeaf(set_leaf->origin());
      for (auto on = set_leaf->getValueMask().beginOn(); on; ++on) {
        updater.apply(*leaf, prox_leaf, on.pos(), true);
        ++stats.voxels_hit;
      }
    }
  }

  // --- proximity marks, after the occupancy update (SEMANTICS.md "The map") -------------------
  if (config_.proximity_range <= 0.0 || stats.hits == 0) return stats;
  openvdb::tree::ValueAccessor<const openvdb::FloatTree> measured_acc(grids_->log_odds->tree());
  // Each hit ray continued beyond its hit point for proximity_range; the k-th voxel after the
  // hit voxel (k >= 1) is a candidate at distance k, the smallest kept.
  const auto range_f = static_cast<float>(config_.proximity_range);
  std::vector<Eigen::Vector3f> starts, beyond;
  starts.reserve(stats.hits);
  beyond.reserve(stats.hits);
  for (std::size_t i = 0; i < points_world.size(); ++i) {
    if (kinds[i] != ScanRays::kHit) continue;
    const Eigen::Vector3f& p = points_world[i];
    const Eigen::Vector3f end = pointAlong(p, octomapNormalized(p - origin_world), range_f);
    if (!lattice_.inRange(end)) continue;
    starts.push_back(p);
    beyond.push_back(end);
  }
  // A ray of length L crosses at most 3 L / resolution + 3 voxels: distances fit a byte when
  // that is below 256.
  const double reach_voxels = std::ceil(config_.proximity_range / config_.resolution) + 2.0;
  DenseScratch marks(lattice_.worldToIndex(hit_min_m) - Index3::Constant(static_cast<int>(reach_voxels)),
                     lattice_.worldToIndex(hit_max_m) + Index3::Constant(static_cast<int>(reach_voxels)));
  if (3.0 * reach_voxels + 3.0 < 256.0 && reach_voxels < 1e6 &&
      marks.bytes() <= options.max_scratch_bytes) {
    marks.allocate();
    Overflow<ProximityMark> outside;
    const kernels::OutsideSink to_outside = [&outside](const Index3& ijk, std::uint8_t d) {
      outside.push({ijk, d});
    };
    const kernels::MarkSpec nearest{kernels::MarkSpec::Mode::MinStepIndex, 0};
    runFor(starts.size(), options, [&](const tbb::blocked_range<std::size_t>& range) {
      kernels::markRays(std::span(starts).subspan(range.begin(), range.size()),
                        std::span(beyond).subspan(range.begin(), range.size()), lattice_, marks.box(),
                        nearest, to_outside, isa);
    });
    // Leaf by leaf: the measured leaf is fetched once, the proximity leaf only when needed.
    openvdb::Coord leaf_origin(std::numeric_limits<int>::max());
    const openvdb::FloatTree::LeafNodeType* measured_leaf = nullptr;
    bool measured_tile = false;
    openvdb::Int32Tree::LeafNodeType* prox_leaf = nullptr;
    marks.forEachSet([&](const openvdb::Coord& origin, openvdb::Index n, std::uint8_t d) {
      if (origin != leaf_origin) {
        leaf_origin = origin;
        measured_leaf = measured_acc.probeConstLeaf(origin);
        measured_tile = measured_leaf == nullptr && measured_acc.isValueOn(origin);
        prox_leaf = nullptr;
      }
      if (measured_tile || (measured_leaf != nullptr && measured_leaf->isValueOn(n))) return;
      if (prox_leaf == nullptr) {
        prox_leaf = prox_acc.touchLeaf(origin);
        noteChanged(toIndex(origin));
      }
      if (prox_leaf->isValueOn(n) && prox_leaf->getValue(n) <= d) return;
      prox_leaf->setValueOn(n, d);
      ++stats.voxels_marked;
    });
    for (const ProximityMark& mark : outside.items()) {
      noteChanged(mark.ijk);
      if (applyMark(prox_acc, measured_acc, toCoord(mark.ijk), mark.distance)) ++stats.voxels_marked;
    }
  } else {
    ProximityBody candidates(starts, beyond, lattice_);
    runReduce(starts.size(), options, candidates);
    for (auto it = candidates.marks.cbeginValueOn(); it; ++it) {
      if (applyMark(prox_acc, measured_acc, it.getCoord(), *it)) {
        noteChanged(toIndex(it.getCoord()));
        ++stats.voxels_marked;
      }
    }
  }
  return stats;
}

float OccupancyMap::logOdds(const Index3& ijk) const {
  float value = 0.0f;
  return grids_->log_odds->tree().probeValue(toCoord(ijk), value) ? value : 0.0f;
}

double OccupancyMap::probability(const Index3& ijk) const { return probabilityOf(logOdds(ijk)); }

bool OccupancyMap::isMeasured(const Index3& ijk) const {
  return grids_->log_odds->tree().isValueOn(toCoord(ijk));
}

std::optional<std::int32_t> OccupancyMap::proximity(const Index3& ijk) const {
  std::int32_t value = 0;
  if (grids_->proximity->tree().probeValue(toCoord(ijk), value)) return value;
  return std::nullopt;
}

std::size_t OccupancyMap::measuredCount() const {
  return static_cast<std::size_t>(grids_->log_odds->tree().activeVoxelCount());
}

std::size_t OccupancyMap::countMeasured(const std::function<bool(float)>& counts) const {
  std::size_t count = 0;
  for (auto it = grids_->log_odds->tree().cbeginValueOn(); it; ++it) {
    if (counts(*it)) count += it.getVoxelCount();
  }
  return count;
}

std::size_t OccupancyMap::occupiedCount() const {
  return countMeasured([this](float l) { return probabilityOf(l) > config_.occupied_threshold; });
}

std::size_t OccupancyMap::freeCount() const {
  return countMeasured([this](float l) { return probabilityOf(l) < config_.free_threshold; });
}

std::size_t OccupancyMap::octomapOccupiedCount() const {
  return countMeasured([](float l) { return l > 0.0f; });
}

std::size_t OccupancyMap::markedCount() const {
  return static_cast<std::size_t>(grids_->proximity->tree().activeVoxelCount());
}

std::optional<Eigen::AlignedBox3i> OccupancyMap::measuredBoundsIndex() const {
  openvdb::CoordBBox bbox;
  if (!grids_->log_odds->tree().evalActiveVoxelBoundingBox(bbox)) return std::nullopt;
  return Eigen::AlignedBox3i(toIndex(bbox.min()), toIndex(bbox.max()));
}

std::optional<Eigen::AlignedBox3d> OccupancyMap::measuredBoundsWorld() const {
  const auto bounds = measuredBoundsIndex();
  if (!bounds) return std::nullopt;
  const double r = config_.resolution;
  return Eigen::AlignedBox3d(bounds->min().cast<double>() * r,
                             (bounds->max().cast<double>() + Eigen::Vector3d::Ones()) * r);
}

std::size_t OccupancyMap::memoryBytes() const {
  return static_cast<std::size_t>(grids_->log_odds->memUsage() + grids_->proximity->memUsage());
}

std::vector<MeasuredVoxel> OccupancyMap::measuredVoxels() const {
  std::vector<MeasuredVoxel> voxels;
  voxels.reserve(measuredCount());
  // Tiles are never created by integrate(), but a loaded file may hold them: expand them.
  for (auto it = grids_->log_odds->tree().cbeginValueOn(); it; ++it) {
    const openvdb::CoordBBox box = it.getBoundingBox();
    for (auto c = box.begin(); c; ++c) voxels.push_back({toIndex(*c), *it});
  }
  std::sort(voxels.begin(), voxels.end(),
            [](const MeasuredVoxel& a, const MeasuredVoxel& b) { return lessIjk(a.ijk, b.ijk); });
  return voxels;
}

void OccupancyMap::forEachMeasuredIn(const Eigen::AlignedBox3i& box,
                                     const std::function<void(const Index3&, float)>& visit) const {
  if (box.isEmpty()) return;
  const openvdb::CoordBBox clip(toCoord(box.min()), toCoord(box.max()));
  const auto& tree = grids_->log_odds->tree();
  if (tree.hasActiveTiles()) {  // only loaded files hold tiles: the general walk, voxel by voxel
    for (auto it = tree.cbeginValueOn(); it; ++it) {
      const openvdb::CoordBBox cells = it.getBoundingBox();
      if (!clip.hasOverlap(cells)) continue;
      for (auto c = cells.begin(); c; ++c) {
        if (clip.isInside(*c)) visit(toIndex(*c), *it);
      }
    }
    return;
  }
  for (auto leaf = tree.cbeginLeaf(); leaf; ++leaf) {
    if (!clip.hasOverlap(leaf->getNodeBoundingBox())) continue;
    for (auto v = leaf->cbeginValueOn(); v; ++v) {
      if (clip.isInside(v.getCoord())) visit(toIndex(v.getCoord()), *v);
    }
  }
}

std::vector<ProximityMark> OccupancyMap::proximityMarks() const {
  std::vector<ProximityMark> marks;
  marks.reserve(markedCount());
  for (auto it = grids_->proximity->tree().cbeginValueOn(); it; ++it) {
    const openvdb::CoordBBox box = it.getBoundingBox();
    for (auto c = box.begin(); c; ++c) marks.push_back({toIndex(*c), *it});
  }
  std::sort(marks.begin(), marks.end(),
            [](const ProximityMark& a, const ProximityMark& b) { return lessIjk(a.ijk, b.ijk); });
  return marks;
}

void OccupancyMap::beginChange() {
  revision_ = nextRevision();
  if (change_log_.size() >= kMaxChangeLog) {  // forget the history rather than grow forever
    change_log_.clear();
    history_start_ = revision_ - 1;
  }
}

void OccupancyMap::noteChanged(const Index3& ijk) {
  const Index3 block(ijk.x() & ~7, ijk.y() & ~7, ijk.z() & ~7);
  if (!change_log_.empty() && change_log_.back().block == block) {  // runs of one block: one record
    change_log_.back().revision = revision_;
    return;
  }
  change_log_.push_back({revision_, block});
}

std::optional<std::vector<Index3>> OccupancyMap::changedBlocksSince(std::uint64_t revision) const {
  if (revision < history_start_ || revision > revision_) return std::nullopt;
  const auto first = std::upper_bound(change_log_.begin(), change_log_.end(), revision,
                                      [](std::uint64_t r, const BlockChange& c) { return r < c.revision; });
  std::vector<Index3> blocks;
  for (auto it = first; it != change_log_.end(); ++it) blocks.push_back(it->block);
  std::sort(blocks.begin(), blocks.end(), lessIjk);
  blocks.erase(std::unique(blocks.begin(), blocks.end()), blocks.end());
  return blocks;
}

void OccupancyMap::setLogOdds(const Index3& ijk, float log_odds) {
  if (!std::isfinite(log_odds)) {
    throw InvalidArgument("log-odds " + std::to_string(log_odds) + " is not finite");
  }
  const float value = std::clamp(log_odds, logOddsOf(config_.clamp_min), logOddsOf(config_.clamp_max));
  beginChange();
  noteChanged(ijk);
  grids_->log_odds->tree().setValueOn(toCoord(ijk), value);
  grids_->proximity->tree().setValueOff(toCoord(ijk), 0);
}

void OccupancyMap::setProximity(const Index3& ijk, std::int32_t distance) {
  if (distance < 1) {
    throw InvalidArgument("proximity distance " + std::to_string(distance) + " must be >= 1");
  }
  if (isMeasured(ijk)) {
    throw InvalidArgument("cannot mark measured voxel (" + std::to_string(ijk.x()) + ", " +
                          std::to_string(ijk.y()) + ", " + std::to_string(ijk.z()) + ")");
  }
  beginChange();
  noteChanged(ijk);
  grids_->proximity->tree().setValueOn(toCoord(ijk), distance);
}

}  // namespace nbv::grid
