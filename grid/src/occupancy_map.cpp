#include "nbv/grid/occupancy_map.hpp"

#include "nbv/errors.hpp"
#include "nbv/kernels/information_gain.hpp"
#include "vdb_grids.hpp"

#include <openvdb/tree/ValueAccessor.h>

#include <algorithm>
#include <array>
#include <atomic>
#include <bit>
#include <functional>
#include <limits>
#include <cmath>
#include <string>

namespace nbv::grid {

openvdb::math::Transform::Ptr makeTransform(double resolution) {
  auto transform = openvdb::math::Transform::createLinearTransform(resolution);
  transform->postTranslate(openvdb::Vec3d(0.5 * resolution));
  return transform;
}

void initializeOpenVdb() {
  static std::once_flag once;
  std::call_once(once, [] { openvdb::initialize(); });
}

namespace {
bool openUnit(double p) { return std::isfinite(p) && p > 0.0 && p < 1.0; }
}  // namespace

// The rules' texts name these limits.
static_assert(MapConfig::kMinResolution == 1e-4 && MapConfig::kMaxProximitySteps == 20000);

void MapConfig::validate() const {
  const MapConfig& c = *this;
#define NBV_MAP_CONFIG_CHECK(name, default_value, unit, check, rule, help)                                  \
  if (const double v = c.name; !(check)) {                                                                    \
    throw InvalidArgument("invalid map configuration: " #name " = " + numberText(v) + " (" rule ")");        \
  }
  NBV_MAP_CONFIG_FIELDS(NBV_MAP_CONFIG_CHECK)
#undef NBV_MAP_CONFIG_CHECK
}

std::span<const MapConfigField> mapConfigFields() {
  static constexpr MapConfigField kFields[] = {
#define NBV_MAP_CONFIG_ROW(name, default_value, unit, check, rule, help) \
  {#name, &MapConfig::name, default_value, unit, rule, help},
      NBV_MAP_CONFIG_FIELDS(NBV_MAP_CONFIG_ROW)
#undef NBV_MAP_CONFIG_ROW
  };
  return kFields;
}

const MapConfigField* mapConfigField(std::string_view name) {
  for (const MapConfigField& f : mapConfigFields()) {
    if (name == f.name) return &f;
  }
  return nullptr;
}

std::string mapConfigFieldNames() {
  std::string names;
  for (const MapConfigField& f : mapConfigFields()) names += (names.empty() ? "" : ", ") + std::string(f.name);
  return names;
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
  grids_->log_odds = LogOddsGrid::create(0.0f);
  grids_->log_odds->setTransform(transform);
  grids_->log_odds->setName("occupancy_log_odds");
  grids_->proximity = MarkGrid::create(0);
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

/// One voxel's occupancy update, as OctoMap's updateNodeLogOdds: add in single precision,
/// then clamp. Also removes the voxel's proximity mark (measured voxels are never marked).
struct VoxelUpdater {
  float hit_log, miss_log, min_log, max_log;

  void apply(LogOddsTree::LeafNodeType& leaf, MarkTree::LeafNodeType* prox_leaf,
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
bool applyMark(openvdb::tree::ValueAccessor<MarkTree>& prox_acc,
               openvdb::tree::ValueAccessor<const LogOddsTree>& measured_acc,
               const openvdb::Coord& xyz, std::int32_t d) {
  if (measured_acc.isValueOn(xyz)) return false;
  MarkTree::ValueType current;
  if (prox_acc.probeValue(xyz, current) && current <= d) return false;
  prox_acc.setValueOn(xyz, static_cast<MarkTree::ValueType>(d));
  return true;
}

openvdb::Index leafOffset(const Index3& ijk) {
  return static_cast<openvdb::Index>(((ijk.x() & 7) << 6) | ((ijk.y() & 7) << 3) | (ijk.z() & 7));
}

}  // namespace

ScanStats OccupancyMap::integrate(std::span<const Eigen::Vector3f> points_world,
                                  const Eigen::Vector3f& origin_world,
                                  const IntegrateOptions& options) {
  return integrate(ScanUpdate(config_, points_world, origin_world, options), options);
}

std::string beyondRangeWarning(const ScanStats& stats, const MapConfig& config) {
  if (stats.beyond_range == 0 || stats.beyond_range <= stats.hits) return "";
  return std::to_string(stats.beyond_range) + " of the scan's " + std::to_string(stats.points) +
         " points lie beyond the map's max_range of " + numberText(config.max_range) +
         " m: they only cleared free space up to it and added no hit (a map for a longer sensor needs a larger "
         "max_range, also when it is loaded from an OctoMap file, which stores none)";
}

ScanStats OccupancyMap::integrate(const ScanUpdate& update, const IntegrateOptions& options) {
  if (!update.config().marksSameVoxels(config_)) {
    throw InvalidArgument("the scan update was marked for another map (resolution, ranges or proximity_range differ)");
  }
  ScanStats stats = update.points();
  beginChange();
  // The cap is checked before the map is touched; near it, the voxels this scan would add are counted.
  openvdb::tree::ValueAccessor<LogOddsTree> log_acc(grids_->log_odds->tree());
  if (options.max_measured_voxels > 0 && measuredCount() + update.voxelCount() > options.max_measured_voxels) {
    std::size_t added = 0;
    for (const ScanUpdate::OccupancyBlock& block : update.occupancy_) {
      const auto* measured = log_acc.probeConstLeaf(toCoord(block.origin));
      forEachBit(unionOf(block.crossed, block.hit), [&](openvdb::Index n) { added += measured == nullptr || !measured->isValueOn(n); });
    }
    for (const Index3& ijk : update.misses_outside_) added += !log_acc.isValueOn(toCoord(ijk));
    const std::size_t total = measuredCount() + added;
    if (total > options.max_measured_voxels) {
      throw CapacityError("the scan would leave " + std::to_string(total) + " measured voxels, above the cap of " +
                          std::to_string(options.max_measured_voxels) + " (IntegrateOptions::max_measured_voxels)");
    }
  }
  applyOccupancy(update, stats);
  if (stats.hits > 0 && config_.proximity_range > 0.0) applyProximity(update, stats);
  return stats;
}

void OccupancyMap::applyOccupancy(const ScanUpdate& update, ScanStats& stats) {
  // Each voxel once, a hit or a miss, as OctoMap's updateNodeLogOdds.
  const VoxelUpdater updater{logOddsOf(config_.p_hit), logOddsOf(config_.p_miss), logOddsOf(config_.clamp_min),
                             logOddsOf(config_.clamp_max)};
  openvdb::tree::ValueAccessor<LogOddsTree> log_acc(grids_->log_odds->tree());
  openvdb::tree::ValueAccessor<MarkTree> prox_acc(grids_->proximity->tree());
  for (const ScanUpdate::OccupancyBlock& block : update.occupancy_) {
    const openvdb::Coord origin = toCoord(block.origin);
    noteChanged(block.origin);
    auto* leaf = log_acc.touchLeaf(origin);
    auto* prox_leaf = prox_acc.probeLeaf(origin);
    forEachBit(unionOf(block.crossed, block.hit), [&](openvdb::Index n) {
      const bool is_hit = hasBit(block.hit, n);
      updater.apply(*leaf, prox_leaf, n, is_hit);
      ++(is_hit ? stats.voxels_hit : stats.voxels_missed);
    });
  }
  for (const Index3& ijk : update.misses_outside_) {
    noteChanged(ijk);
    const openvdb::Coord xyz = toCoord(ijk);
    updater.apply(*log_acc.touchLeaf(xyz), prox_acc.probeLeaf(xyz), leafOffset(ijk), false);
    ++stats.voxels_missed;
  }
}

void OccupancyMap::applyProximity(const ScanUpdate& update, ScanStats& stats) {
  // After the occupancy update (SEMANTICS.md "The map"): a candidate marks a voxel unless it is
  // measured, and a mark only ever lowers. Block by block: the measured leaf is fetched once,
  // the proximity leaf only when needed.
  openvdb::tree::ValueAccessor<const LogOddsTree> measured_acc(grids_->log_odds->tree());
  openvdb::tree::ValueAccessor<MarkTree> prox_acc(grids_->proximity->tree());
  for (const ScanUpdate::MarkBlock& block : update.marks_) {
    const openvdb::Coord origin = toCoord(block.origin);
    const auto* measured_leaf = measured_acc.probeConstLeaf(origin);
    const bool measured_tile = measured_leaf == nullptr && measured_acc.isValueOn(origin);
    MarkTree::LeafNodeType* prox_leaf = nullptr;
    std::size_t next = block.first;
    forEachBit(block.marked, [&](openvdb::Index n) {
      const std::int32_t d = update.distances_[next++];
      if (measured_tile || (measured_leaf != nullptr && measured_leaf->isValueOn(n))) return;
      if (prox_leaf == nullptr) {
        prox_leaf = prox_acc.touchLeaf(origin);
        noteChanged(block.origin);
      }
      if (prox_leaf->isValueOn(n) && prox_leaf->getValue(n) <= d) return;
      prox_leaf->setValueOn(n, static_cast<MarkTree::ValueType>(d));
      ++stats.voxels_marked;
    });
  }
  for (const ProximityMark& mark : update.marks_outside_) {
    if (applyMark(prox_acc, measured_acc, toCoord(mark.ijk), mark.distance)) {
      noteChanged(mark.ijk);
      ++stats.voxels_marked;
    }
  }
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
  MarkTree::ValueType value = 0;
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
  return countMeasured([](float l) { return l >= 0.0f; });
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

void OccupancyMap::copyMeasuredLogOdds(const Eigen::AlignedBox3i& box, std::span<float> dense) const {
  const std::size_t voxels = box.isEmpty() ? 0 : static_cast<std::size_t>((box.sizes() + Index3::Ones()).cast<std::int64_t>().prod());
  if (dense.size() != voxels) {
    throw InvalidArgument("copyMeasuredLogOdds: " + std::to_string(dense.size()) + " values for a box of " +
                          std::to_string(voxels) + " voxels");
  }
  if (voxels == 0) return;
  const openvdb::CoordBBox clip(toCoord(box.min()), toCoord(box.max()));
  const auto nj = static_cast<std::size_t>(box.sizes().y()) + 1, nk = static_cast<std::size_t>(box.sizes().z()) + 1;
  const auto at = [&](const openvdb::Coord& c) {
    const openvdb::Coord r = c - clip.min();
    return (static_cast<std::size_t>(r.x()) * nj + static_cast<std::size_t>(r.y())) * nk + static_cast<std::size_t>(r.z());
  };
  const auto& tree = grids_->log_odds->tree();
  if (tree.hasActiveTiles()) {  // tiles (nbv writes and loads voxels only): the general walk
    for (auto it = tree.cbeginValueOn(); it; ++it) {
      openvdb::CoordBBox cells = it.getBoundingBox();
      if (!clip.hasOverlap(cells)) continue;
      cells.intersect(clip);  // a tile may be far larger than the box
      for (auto c = cells.begin(); c; ++c) dense[at(*c)] = *it;
    }
    return;
  }
  for (auto leaf = tree.cbeginLeaf(); leaf; ++leaf) {
    const openvdb::CoordBBox cells = leaf->getNodeBoundingBox();
    if (!clip.hasOverlap(cells)) continue;
    const bool inside = clip.isInside(cells);
    for (auto v = leaf->cbeginValueOn(); v; ++v) {
      const openvdb::Coord c = v.getCoord();
      if (inside || clip.isInside(c)) dense[at(c)] = *v;
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
    throw InvalidArgument("log-odds " + numberText(log_odds) + " is not finite");
  }
  const float value = std::clamp(log_odds, logOddsOf(config_.clamp_min), logOddsOf(config_.clamp_max));
  beginChange();
  noteChanged(ijk);
  grids_->log_odds->tree().setValueOn(toCoord(ijk), value);
  grids_->proximity->tree().setValueOff(toCoord(ijk), 0);
}

void OccupancyMap::setProximity(const Index3& ijk, std::int32_t distance) {
  if (distance < 1 || distance > Config::kMaxProximityDistance) {
    throw InvalidArgument("proximity distance " + std::to_string(distance) + " must be in [1, " +
                          std::to_string(Config::kMaxProximityDistance) + "]");
  }
  if (isMeasured(ijk)) {
    throw InvalidArgument("cannot mark measured voxel (" + std::to_string(ijk.x()) + ", " +
                          std::to_string(ijk.y()) + ", " + std::to_string(ijk.z()) + ")");
  }
  beginChange();
  noteChanged(ijk);
  grids_->proximity->tree().setValueOn(toCoord(ijk), static_cast<MarkTree::ValueType>(distance));
}

}  // namespace nbv::grid
