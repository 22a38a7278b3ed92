#include "nbv/grid/occupancy_map.hpp"

#include "nbv/grid/errors.hpp"
#include "vdb_grids.hpp"

#include <openvdb/tree/ValueAccessor.h>
#include <tbb/blocked_range.h>
#include <tbb/parallel_reduce.h>

#include <algorithm>
#include <cmath>
#include <mutex>
#include <sstream>

namespace nbv::grid {

namespace {

std::string formatPoint(const Eigen::Vector3f& p) {
  std::ostringstream out;
  out << '(' << p.x() << ", " << p.y() << ", " << p.z() << ')';
  return out.str();
}

/// The free-space segment of one point and whether its end is a hit (OctoMap's computeUpdate).
struct ScanRay {
  Eigen::Vector3f end;
  bool hit;
};

/// A set of voxels collected by one TBB task; tasks join by union, so the result does not
/// depend on how TBB splits the work.
struct VoxelSetBody {
  const std::vector<ScanRay>* rays;
  const Eigen::Vector3f* origin;
  const VoxelLattice* lattice;
  openvdb::MaskTree crossed;

  VoxelSetBody(const std::vector<ScanRay>& r, const Eigen::Vector3f& o, const VoxelLattice& l)
      : rays(&r), origin(&o), lattice(&l) {}
  VoxelSetBody(VoxelSetBody& other, tbb::split)
      : rays(other.rays), origin(other.origin), lattice(other.lattice) {}

  void operator()(const tbb::blocked_range<std::size_t>& range) {
    openvdb::tree::ValueAccessor<openvdb::MaskTree> acc(crossed);
    for (std::size_t i = range.begin(); i != range.end(); ++i) {
      traverseRayKeys(*origin, (*rays)[i].end, *lattice,
                      [&acc](const Index3& ijk) { acc.setValueOn(toCoord(ijk)); });
    }
  }
  void join(VoxelSetBody& other) { crossed.topologyUnion(other.crossed); }
};

/// Proximity candidates of one TBB task: the smallest distance per voxel; join keeps minima.
struct ProximityBody {
  const std::vector<Eigen::Vector3f>* hit_points;
  const Eigen::Vector3f* origin;
  const VoxelLattice* lattice;
  const openvdb::FloatTree* measured;
  float range_m;
  openvdb::Int32Tree marks{0};

  ProximityBody(const std::vector<Eigen::Vector3f>& h, const Eigen::Vector3f& o,
                const VoxelLattice& l, const openvdb::FloatTree& m, float r)
      : hit_points(&h), origin(&o), lattice(&l), measured(&m), range_m(r) {}
  ProximityBody(ProximityBody& other, tbb::split)
      : hit_points(other.hit_points), origin(other.origin), lattice(other.lattice),
        measured(other.measured), range_m(other.range_m) {}

  void operator()(const tbb::blocked_range<std::size_t>& range) {
    openvdb::tree::ValueAccessor<openvdb::Int32Tree> acc(marks);
    openvdb::tree::ValueAccessor<const openvdb::FloatTree> measured_acc(*measured);
    for (std::size_t i = range.begin(); i != range.end(); ++i) {
      const Eigen::Vector3f& p = (*hit_points)[i];
      // SPEC §1: continue the ray direction beyond the hit voxel for proximity_range.
      const Eigen::Vector3f direction = octomapNormalized(p - *origin);
      const Eigen::Vector3f beyond(p.x() + direction.x() * range_m, p.y() + direction.y() * range_m,
                                   p.z() + direction.z() * range_m);
      if (!lattice->inRange(beyond)) continue;
      std::int32_t k = 0;  // k-th voxel behind the hit voxel; the hit voxel itself is k = 0
      traverseRayKeys(p, beyond, *lattice, [&](const Index3& ijk) {
        const std::int32_t d = k++;
        if (d == 0) return;
        const openvdb::Coord xyz = toCoord(ijk);
        if (measured_acc.isValueOn(xyz)) return;  // measured voxels are never marked
        std::int32_t current;
        if (!acc.probeValue(xyz, current) || d < current) acc.setValueOn(xyz, d);
      });
    }
  }
  void join(ProximityBody& other) { mergeMinimum(marks, other.marks); }

  static void mergeMinimum(openvdb::Int32Tree& into, const openvdb::Int32Tree& from) {
    openvdb::tree::ValueAccessor<openvdb::Int32Tree> acc(into);
    for (auto it = from.cbeginValueOn(); it; ++it) {
      std::int32_t current;
      if (!acc.probeValue(it.getCoord(), current) || *it < current) {
        acc.setValueOn(it.getCoord(), *it);
      }
    }
  }
};

template <class Body>
void runReduce(std::size_t count, const ParallelOptions& parallel, Body& body) {
  if (count == 0) return;
  if (parallel.serial) {
    body(tbb::blocked_range<std::size_t>(0, count));
  } else {
    tbb::parallel_reduce(
        tbb::blocked_range<std::size_t>(0, count, std::max<std::size_t>(1, parallel.grain_size)),
        body);
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

float OccupancyMap::logOddsOf(double probability) {
  return static_cast<float>(std::log(probability / (1.0 - probability)));
}

OccupancyMap::OccupancyMap(const Config& config)
    : config_(config), lattice_(config.resolution), grids_(std::make_unique<Grids>()) {
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
    : config_(other.config_), lattice_(other.lattice_), grids_(std::make_unique<Grids>()) {
  grids_->log_odds = other.grids_->log_odds->deepCopy();
  grids_->proximity = other.grids_->proximity->deepCopy();
}

OccupancyMap& OccupancyMap::operator=(const OccupancyMap& other) {
  if (this != &other) *this = OccupancyMap(other);
  return *this;
}

ScanStats OccupancyMap::integrate(const std::vector<Eigen::Vector3f>& points_world,
                                  const Eigen::Vector3f& origin_world,
                                  const ParallelOptions& parallel) {
  if (!lattice_.inRange(origin_world)) {
    throw InvalidArgument("sensor origin " + formatPoint(origin_world) +
                          " is not finite or outside the map's index range");
  }
  ScanStats stats;
  stats.points = points_world.size();

  // OctoMap's computeUpdate: a point within max_range gives a ray to it and a hit; a point
  // beyond gives a ray to origin + direction * max_range and no hit.
  std::vector<ScanRay> rays;
  std::vector<Eigen::Vector3f> hit_points;
  rays.reserve(points_world.size());
  const auto max_range_f = static_cast<float>(config_.max_range);
  for (const Eigen::Vector3f& p : points_world) {
    if (!lattice_.inRange(p)) {
      ++stats.skipped_points;
      continue;
    }
    const Eigen::Vector3f offset = p - origin_world;
    if (octomapNorm(offset) <= config_.max_range) {
      rays.push_back({p, true});
      hit_points.push_back(p);
      ++stats.hits;
    } else {
      const Eigen::Vector3f direction = octomapNormalized(offset);
      const Eigen::Vector3f end(origin_world.x() + direction.x() * max_range_f,
                                origin_world.y() + direction.y() * max_range_f,
                                origin_world.z() + direction.z() * max_range_f);
      if (!lattice_.inRange(end)) {
        ++stats.skipped_points;
        continue;
      }
      rays.push_back({end, false});
      ++stats.beyond_range;
    }
  }

  // The two voxel sets of the scan: crossed (misses) and end voxels (hits).
  VoxelSetBody crossed(rays, origin_world, lattice_);
  runReduce(rays.size(), parallel, crossed);
  openvdb::MaskTree hit_set;
  {
    openvdb::tree::ValueAccessor<openvdb::MaskTree> acc(hit_set);
    for (const Eigen::Vector3f& p : hit_points) acc.setValueOn(toCoord(lattice_.worldToIndex(p)));
  }

  // Each voxel updated once: a hit if it is an end voxel, else a miss (hits win).
  const float hit_log = logOddsOf(config_.p_hit);
  const float miss_log = logOddsOf(config_.p_miss);
  const float min_log = logOddsOf(config_.clamp_min);
  const float max_log = logOddsOf(config_.clamp_max);
  openvdb::tree::ValueAccessor<openvdb::FloatTree> log_acc(grids_->log_odds->tree());
  openvdb::tree::ValueAccessor<openvdb::Int32Tree> prox_acc(grids_->proximity->tree());
  openvdb::tree::ValueAccessor<const openvdb::MaskTree> hit_acc(hit_set);
  auto update_leaf = [&](const openvdb::MaskTree::LeafNodeType& set_leaf, bool is_hit) {
    const openvdb::Coord leaf_origin = set_leaf.origin();
    auto* leaf = log_acc.touchLeaf(leaf_origin);
    auto* prox_leaf = prox_acc.probeLeaf(leaf_origin);
    const auto* hit_leaf = is_hit ? nullptr : hit_acc.probeConstLeaf(leaf_origin);
    std::size_t updated = 0;
    for (auto on = set_leaf.getValueMask().beginOn(); on; ++on) {
      const openvdb::Index n = on.pos();
      if (hit_leaf != nullptr && hit_leaf->isValueOn(n)) continue;  // the hit wins
      const float current = leaf->isValueOn(n) ? leaf->getValue(n) : 0.0f;
      // OctoMap's updateNodeLogOdds: add in single precision, then clamp.
      float value = current + (is_hit ? hit_log : miss_log);
      if (value < min_log) {
        value = min_log;
      } else if (value > max_log) {
        value = max_log;
      }
      leaf->setValueOn(n, value);
      if (prox_leaf != nullptr && prox_leaf->isValueOn(n)) prox_leaf->setValueOff(n, 0);
      ++updated;
    }
    return updated;
  };
  for (auto leaf = crossed.crossed.cbeginLeaf(); leaf; ++leaf) {
    stats.voxels_missed += update_leaf(*leaf, false);
  }
  for (auto leaf = hit_set.cbeginLeaf(); leaf; ++leaf) stats.voxels_hit += update_leaf(*leaf, true);

  // Proximity marks after the occupancy update (SPEC §1).
  if (config_.proximity_range > 0.0 && !hit_points.empty()) {
    ProximityBody marks(hit_points, origin_world, lattice_, grids_->log_odds->tree(),
                        static_cast<float>(config_.proximity_range));
    runReduce(hit_points.size(), parallel, marks);
    const std::size_t before = grids_->proximity->tree().activeVoxelCount();
    std::size_t lowered = 0;
    for (auto it = marks.marks.cbeginValueOn(); it; ++it) {
      std::int32_t current;
      if (!prox_acc.probeValue(it.getCoord(), current)) {
        prox_acc.setValueOn(it.getCoord(), *it);
      } else if (*it < current) {
        prox_acc.setValueOn(it.getCoord(), *it);
        ++lowered;
      }
    }
    stats.voxels_marked = grids_->proximity->tree().activeVoxelCount() - before + lowered;
  }
  return stats;
}

float OccupancyMap::logOdds(const Index3& ijk) const {
  float value = 0.0f;
  return grids_->log_odds->tree().probeValue(toCoord(ijk), value) ? value : 0.0f;
}

double OccupancyMap::probability(const Index3& ijk) const {
  return 1.0 / (1.0 + std::exp(-static_cast<double>(logOdds(ijk))));
}

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

std::size_t OccupancyMap::occupiedCount() const {
  std::size_t count = 0;
  for (auto it = grids_->log_odds->tree().cbeginValueOn(); it; ++it) {
    if (1.0 / (1.0 + std::exp(-static_cast<double>(*it))) > config_.occupied_threshold) {
      count += it.getVoxelCount();
    }
  }
  return count;
}

std::size_t OccupancyMap::freeCount() const {
  std::size_t count = 0;
  for (auto it = grids_->log_odds->tree().cbeginValueOn(); it; ++it) {
    if (1.0 / (1.0 + std::exp(-static_cast<double>(*it))) < config_.free_threshold) {
      count += it.getVoxelCount();
    }
  }
  return count;
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

namespace {
bool lessIjk(const Index3& a, const Index3& b) {
  return std::lexicographical_compare(a.data(), a.data() + 3, b.data(), b.data() + 3);
}
}  // namespace

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

void OccupancyMap::setLogOdds(const Index3& ijk, float log_odds) {
  if (!std::isfinite(log_odds)) {
    throw InvalidArgument("log-odds " + std::to_string(log_odds) + " is not finite");
  }
  const float value = std::clamp(log_odds, logOddsOf(config_.clamp_min), logOddsOf(config_.clamp_max));
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
  grids_->proximity->tree().setValueOn(toCoord(ijk), distance);
}

}  // namespace nbv::grid
