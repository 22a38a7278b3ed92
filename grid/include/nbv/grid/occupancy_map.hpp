#pragma once
/// \file The probabilistic occupancy map of record (SEMANTICS.md "The map"), on OpenVDB.

#include "nbv/grid/depth_image.hpp"
#include "nbv/kernels/mark_rays.hpp"
#include "nbv/kernels/ray_keys.hpp"

#include <Eigen/Core>
#include <Eigen/Geometry>

#include <array>
#include <cstddef>
#include <cstdint>
#include <functional>
#include <memory>
#include <optional>
#include <span>
#include <string>
#include <string_view>
#include <vector>

namespace nbv::grid {

using kernels::Index3;
using kernels::VoxelLattice;

/// One measured voxel: its index and its occupancy log-odds.
struct MeasuredVoxel {
  Index3 ijk;
  float log_odds;
};

/// One proximity mark: an unmeasured voxel `distance` voxel steps behind an observed surface.
struct ProximityMark {
  Index3 ijk;
  std::int32_t distance;
};

/// What one call of OccupancyMap::integrate() did.
struct ScanStats {
  std::size_t points = 0;            ///< points given
  std::size_t skipped_points = 0;    ///< non-finite or out of the index range: ignored
  std::size_t hits = 0;              ///< points within max_range (each adds a hit)
  std::size_t beyond_range = 0;      ///< points beyond max_range (free space only)
  std::size_t too_near = 0;          ///< points nearer than min_range: dropped
  std::size_t voxels_hit = 0;        ///< distinct voxels updated as hits
  std::size_t voxels_missed = 0;     ///< distinct voxels updated as misses
  std::size_t voxels_marked = 0;     ///< proximity marks set or lowered

  /// Adds another scan's counts (a sequence's totals).
  ScanStats& operator+=(const ScanStats& o) {
    points += o.points;
    skipped_points += o.skipped_points;
    hits += o.hits;
    beyond_range += o.beyond_range;
    too_near += o.too_near;
    voxels_hit += o.voxels_hit;
    voxels_missed += o.voxels_missed;
    voxels_marked += o.voxels_marked;
    return *this;
  }
};

/// Options of OccupancyMap::integrate(): how a scan is computed (threads, scratch, ISA), which
/// never changes the map, the cap, which may refuse a scan, and OctoMap's `discretize`.
struct IntegrateOptions {
  /// Cap on measured voxels: a scan that would leave more is refused (CapacityError) and the
  /// map stays as it was. 0: no cap.
  std::size_t max_measured_voxels = 0;
  bool serial = false;            ///< run on the calling thread only
  std::size_t grain_size = 1024;  ///< rays per TBB task
  /// Largest scratch buffer [bytes] for the dense per-scan voxel sets (one byte per voxel of
  /// the scan's bounding box); a scan whose box needs more uses sparse OpenVDB sets instead,
  /// slower but bounded by the voxels the rays touch.
  std::size_t max_scratch_bytes = std::size_t{1} << 27;
  /// Instruction set of the ray loop; empty: the best this build and CPU support.
  std::optional<kernels::Isa> isa;
  /// OctoMap's `insertPointCloud(..., discretize = true)` (SEMANTICS.md "The map"): the scan's
  /// points are first reduced to one per distinct voxel, that voxel's centre, so a scan casts
  /// one ray per voxel its points end in. Changes the map (a ray ends at the centre, not at the
  /// point); far fewer rays for a dense scan.
  bool discretize = false;
};

/// The fields of MapConfig, each declared once: X(name, default, unit, check, rule, help). A
/// row is a member (a double), a keyword of Python's OccupancyMap(**config) and load_map() and
/// a key of its `config` dict, a flag of the command line where a map is made (`--p-hit`), a
/// key of a .vdb map's metadata ("nbv_" + name), a line of `nbv info` and of their help texts,
/// and a check of MapConfig::validate(): `check`, an expression of the value `v` and the
/// configuration `c`, must hold, else the error names the field, its value and `rule`. Defaults
/// are those of SEMANTICS.md "The map" (= the released code's). A new field is a row at the end
/// (map files written before it lack it and read its default) and its test.
#define NBV_MAP_CONFIG_FIELDS(X)                                                                                  \
  X(resolution, 0.01, "m", std::isfinite(v) && v >= kMinResolution, "must be finite and >= 0.0001 m",              \
    "voxel edge length")                                                                                           \
  X(p_hit, 0.7, "", openUnit(v) && v > 0.5, "must be in (0.5, 1)", "occupancy probability of a hit")              \
  X(p_miss, 0.4, "", openUnit(v) && v < 0.5, "must be in (0, 0.5)", "occupancy probability of a miss")            \
  X(clamp_min, 0.12, "", openUnit(v) && v < 0.5, "must be in (0, 0.5)", "lower probability clamp")                \
  X(clamp_max, 0.97, "", openUnit(v) && v > 0.5, "must be in (0.5, 1)", "upper probability clamp")                \
  X(max_range, 1.5, "m", std::isfinite(v) && v > 0.0, "must be finite and > 0",                                   \
    "points farther than this only clear free space up to it")                                                     \
  X(proximity_range, 0.3, "m", std::isfinite(v) && v >= 0.0 && v <= kMaxProximitySteps * c.resolution,            \
    "must be finite, >= 0 and at most 20000 voxels", "how far behind a hit proximity marks reach (0: none)")        \
  X(occupied_threshold, 0.8, "", openUnit(v), "must be in (0, 1)", "class occupied: probability above this")      \
  X(free_threshold, 0.2, "", openUnit(v) && v <= c.occupied_threshold, "must be in (0, 1) and <= occupied_threshold", \
    "class free: probability below this")                                                                          \
  X(min_range, 0.0, "m", std::isfinite(v) && v >= 0.0 && v < c.max_range, "must be finite, >= 0 and below max_range", \
    "points nearer than this are dropped (a sensor's near limit; 0, OctoMap's, drops none)")

/// The fields of the table's first version (resolution to free_threshold): every .vdb map holds
/// them; a later field may be absent from a file and reads as its default.
inline constexpr std::size_t kFirstMapConfigFields = 9;

/// Sensor model and map parameters (NBV_MAP_CONFIG_FIELDS).
struct MapConfig {
  /// The finest resolution a map takes [m]: OpenVDB refuses a transform whose voxel volume is
  /// near zero (1e-5 m already), and a depth camera resolves no finer.
  static constexpr double kMinResolution = 1e-4;
  /// The largest proximity mark distance [voxel steps] a map holds (marks are 16-bit).
  static constexpr std::int32_t kMaxProximityDistance = 65535;
  /// The longest proximity_range [voxels]: a continuation of that length crosses at most
  /// 3 x 20,000 + 3 voxels, so its distances fit kMaxProximityDistance.
  static constexpr int kMaxProximitySteps = 20000;

#define NBV_MAP_CONFIG_MEMBER(name, default_value, unit, check, rule, help) double name = default_value;
  NBV_MAP_CONFIG_FIELDS(NBV_MAP_CONFIG_MEMBER)
#undef NBV_MAP_CONFIG_MEMBER

  /// Throws InvalidArgument naming the first bad value.
  void validate() const;
  /// True if a scan touches the same voxels under `other`: the same resolution, ranges and
  /// proximity_range (the sensor model and the classes may differ).
  bool marksSameVoxels(const MapConfig& other) const {
    return resolution == other.resolution && max_range == other.max_range && min_range == other.min_range &&
           proximity_range == other.proximity_range;
  }
};

/// A row of NBV_MAP_CONFIG_FIELDS as data, for the front doors that loop over the fields.
struct MapConfigField {
  const char* name;
  double MapConfig::*member;
  double default_value;
  const char* unit;  ///< "m", or "" for a probability
  const char* rule;  ///< what validate() requires of it
  const char* help;  ///< what it is
};
/// The rows of NBV_MAP_CONFIG_FIELDS, in its order.
std::span<const MapConfigField> mapConfigFields();
/// The row named `name`, or null.
const MapConfigField* mapConfigField(std::string_view name);
/// The fields' names, comma-separated in the table's order: what errors and help texts list.
std::string mapConfigFieldNames();

/// A warning when most of a scan's points (`stats`) lay beyond the map's max_range (`config`):
/// they only cleared free space up to it, and added no hit (a map loaded from an OctoMap file
/// with the default 1.5 m keeps only that much of a 6 m scan); empty otherwise.
std::string beyondRangeWarning(const ScanStats& stats, const MapConfig& config);

/// The voxels one scan updates, marked once (SEMANTICS.md "The map"): the voxels its rays
/// cross (misses), the voxels its hits end in, and the proximity candidates behind the hits.
/// Which voxels a scan touches depends on the map's configuration and not on its contents, so
/// a scan that many maps integrate (an experiment's trials, from the same view) is marked once
/// and OccupancyMap::integrate(const ScanUpdate&) applies it to each: the map it leaves is the
/// one integrate() of the points leaves, bit for bit.
class ScanUpdate {
 public:
  /// Marks the rays from `origin_world` to `points_world` as integrate() would, for maps of
  /// `config`. `options` chooses how (threads, scratch size, ISA) and, by `discretize`, whether
  /// the points are reduced to their voxels' centres first.
  /// \throws InvalidArgument if `config` is invalid, or `origin_world` is not finite or out of
  /// the index range.
  ScanUpdate(const MapConfig& config, std::span<const Eigen::Vector3f> points_world,
             const Eigen::Vector3f& origin_world, const IntegrateOptions& options = IntegrateOptions{});

  /// The configuration the scan was marked for; a map integrates it only under an equal one.
  const MapConfig& config() const { return config_; }
  /// The point counts (points, skipped_points, hits, beyond_range); the voxel counts are
  /// integrate()'s, as they depend on the map.
  const ScanStats& points() const { return points_; }
  /// Distinct voxels whose occupancy the scan updates.
  std::size_t voxelCount() const;

 private:
  friend class OccupancyMap;
  /// Bits of one 8^3 block, bit n at OpenVDB's leaf offset n = 64 x + 8 y + z.
  using BlockBits = std::array<std::uint64_t, 8>;
  /// The occupancy updates of one block: each voxel of crossed | hit once, a hit if in `hit`.
  struct OccupancyBlock {
    Index3 origin;
    BlockBits crossed{}, hit{};
  };
  /// The proximity candidates of one block: the distances of the bits of `marked`, in bit
  /// order, from distances_[first].
  struct MarkBlock {
    Index3 origin;
    BlockBits marked{};
    std::size_t first = 0;
  };

  /// What each point adds and the boxes of its rays (defined in scan_update.cpp).
  struct Classified;
  Classified classify(std::span<const Eigen::Vector3f> points_world);
  void markOccupancy(std::span<const Eigen::Vector3f> points_world, const Classified& scan,
                     const IntegrateOptions& options);
  void markProximity(std::span<const Eigen::Vector3f> points_world, const Classified& scan,
                     const IntegrateOptions& options);

  MapConfig config_;
  VoxelLattice lattice_;
  Eigen::Vector3f origin_;
  ScanStats points_;
  std::vector<OccupancyBlock> occupancy_;     ///< the voxels of a dense box
  std::vector<Index3> misses_outside_;        ///< crossed voxels outside it: sorted, unique
  std::vector<MarkBlock> marks_;              ///< the candidates of a dense box
  std::vector<std::uint8_t> distances_;       ///< of marks_
  std::vector<ProximityMark> marks_outside_;  ///< candidates outside it, a voxel possibly more than once
};

/// Probabilistic voxel map: log-odds occupancy per voxel plus proximity marks (SEMANTICS.md "The map").
///
/// Voxels that were never measured read as the prior (log-odds 0, probability 0.5). The map is
/// unbounded; voxel (i, j, k) is centred at ((i, j, k) + 0.5) * resolution, like OctoMap's keys,
/// and the same scans give exactly the log-odds OctoMap's `insertPointCloud` gives.
///
/// Thread-safety: const member functions may be called concurrently; integrate() and the
/// setters need exclusive access (integrate() parallelises internally with TBB).
class OccupancyMap {
 public:
  using Config = MapConfig;

  /// \throws InvalidArgument if `config` is invalid.
  explicit OccupancyMap(const Config& config = Config{});
  ~OccupancyMap();
  OccupancyMap(const OccupancyMap& other);             ///< deep copy
  OccupancyMap& operator=(const OccupancyMap& other);  ///< deep copy
  OccupancyMap(OccupancyMap&&) noexcept;
  OccupancyMap& operator=(OccupancyMap&&) noexcept;

  const Config& config() const { return config_; }
  const VoxelLattice& lattice() const { return lattice_; }

  /// Integrates one scan as OctoMap's insertPointCloud(discretize = false) (SEMANTICS.md "The map"), then
  /// sets the proximity marks. Points are world coordinates [m] in single precision, as OctoMap
  /// stores them; non-finite points are skipped and counted. The result is bit-identical
  /// whatever the thread count or `options`.
  /// \throws InvalidArgument if `origin_world` is not finite or out of the index range;
  /// CapacityError if the scan would exceed `options.max_measured_voxels` (the map unchanged).
  ScanStats integrate(std::span<const Eigen::Vector3f> points_world,
                      const Eigen::Vector3f& origin_world,
                      const IntegrateOptions& options = IntegrateOptions{});
  /// integrate() of a vector (or a braced list) of points.
  ScanStats integrate(const std::vector<Eigen::Vector3f>& points_world, const Eigen::Vector3f& origin_world,
                      const IntegrateOptions& options = IntegrateOptions{}) {
    return integrate(std::span<const Eigen::Vector3f>(points_world), origin_world, options);
  }
  /// Integrates a scan marked beforehand: the same map, stats and change record as integrate()
  /// of its points. Only the cap of `options` is read (how the rays were marked was the
  /// update's choice).
  /// \throws InvalidArgument if `update` was marked for another configuration (resolution,
  /// max_range or proximity_range); CapacityError as integrate().
  ScanStats integrate(const ScanUpdate& update, const IntegrateOptions& options = IntegrateOptions{});

  /// Integrates one depth frame as the cloud backProject() makes of it (SEMANTICS.md "Real
  /// sensor input"), from the camera's position: the same map, voxel for voxel. Under
  /// NoReturn::Clear the no-return points lie at twice the map's max_range.
  /// \throws as backProject() and integrate().
  ScanStats integrateDepth(const DepthImage& depth, const sensor::PinholeCamera& camera,
                           const Eigen::Isometry3d& T_world_camera, const DepthOptions& depth_options = DepthOptions{},
                           const IntegrateOptions& options = IntegrateOptions{});

  // --- queries by index --------------------------------------------------------------------
  /// Log-odds of voxel `ijk`; 0 (the prior) if it was never measured.
  float logOdds(const Index3& ijk) const;
  /// Occupancy probability 1 / (1 + exp(-L)); 0.5 if never measured.
  double probability(const Index3& ijk) const;
  /// True once any scan updated the voxel.
  bool isMeasured(const Index3& ijk) const;
  /// Proximity distance in voxel steps, if the voxel carries a mark (marked voxels are
  /// always unmeasured).
  std::optional<std::int32_t> proximity(const Index3& ijk) const;

  // --- queries by world point [m] -----------------------------------------------------------
  Index3 worldToIndex(const Eigen::Vector3d& p_world) const { return lattice_.worldToIndex(p_world); }
  Eigen::Vector3d indexToWorld(const Index3& ijk) const { return lattice_.indexToWorld(ijk); }
  float logOdds(const Eigen::Vector3d& p_world) const { return logOdds(worldToIndex(p_world)); }
  double probability(const Eigen::Vector3d& p_world) const { return probability(worldToIndex(p_world)); }
  bool isMeasured(const Eigen::Vector3d& p_world) const { return isMeasured(worldToIndex(p_world)); }
  std::optional<std::int32_t> proximity(const Eigen::Vector3d& p_world) const {
    return proximity(worldToIndex(p_world));
  }

  // --- whole-map statistics -----------------------------------------------------------------
  std::size_t measuredCount() const;
  /// Measured voxels with probability above Config::occupied_threshold.
  std::size_t occupiedCount() const;
  /// Measured voxels with probability below Config::free_threshold.
  std::size_t freeCount() const;
  /// Measured voxels OctoMap's isNodeOccupied() calls occupied: log-odds at or above 0 (P >=
  /// 0.5), liboctomap's `>=` against its threshold's log-odds, 0.
  /// One scan leaves its hits at P = 0.7, occupied for OctoMap and not yet for occupiedCount().
  std::size_t octomapOccupiedCount() const;
  /// Voxels with a proximity mark.
  std::size_t markedCount() const;
  /// Inclusive index bounds of the measured voxels; empty if none is measured.
  std::optional<Eigen::AlignedBox3i> measuredBoundsIndex() const;
  /// World bounds [m] of the measured voxels (outer faces); empty if none is measured.
  std::optional<Eigen::AlignedBox3d> measuredBoundsWorld() const;
  /// Bytes held by the voxel grids.
  std::size_t memoryBytes() const;

  /// Every measured voxel, sorted by (i, j, k).
  std::vector<MeasuredVoxel> measuredVoxels() const;
  /// Writes the log-odds of every measured voxel inside the inclusive index box `box` into
  /// `dense`, one value per voxel of the box at ((i - i0) * nj + (j - j0)) * nk + (k - k0) (k
  /// fastest); the values of unmeasured voxels are left as they are. Blocks of the grid outside
  /// the box are skipped whole.
  /// \throws InvalidArgument if `dense` does not hold one value per voxel of the box.
  void copyMeasuredLogOdds(const Eigen::AlignedBox3i& box, std::span<float> dense) const;
  /// Every proximity mark, sorted by (i, j, k).
  std::vector<ProximityMark> proximityMarks() const;

  // --- direct edits (importers, tests) ------------------------------------------------------
  /// Marks the voxel measured with log-odds `log_odds`, clamped to the configured clamps;
  /// removes its proximity mark. \throws InvalidArgument if `log_odds` is not finite.
  void setLogOdds(const Index3& ijk, float log_odds);
  /// Sets a proximity mark on an unmeasured voxel. \throws InvalidArgument if the voxel is
  /// measured or `distance` is outside [1, Config::kMaxProximityDistance].
  void setProximity(const Index3& ijk, std::int32_t distance);

  /// Log-odds of a probability in OctoMap's single precision (octomap::logodds).
  static float logOddsOf(double probability);
  /// Probability 1 / (1 + exp(-L)) of log-odds L.
  static double probabilityOf(float log_odds);

  // --- change tracking (for snapshots that update only what changed) ----------------------
  /// A number that changes whenever the map does; unique across all maps of the process.
  std::uint64_t revision() const { return revision_; }
  /// Origins of the 8^3 blocks (voxel indices that are multiples of 8) changed after
  /// `revision`, sorted and without duplicates; empty optional if the map cannot say (the
  /// revision is from another map or older than the history the map keeps). Not thread-safe
  /// with a concurrent change.
  std::optional<std::vector<Index3>> changedBlocksSince(std::uint64_t revision) const;

  /// Opaque OpenVDB storage; defined in grid/src (see vdb_grids.hpp there).
  struct Grids;
  const Grids& grids() const { return *grids_; }
  Grids& grids() { return *grids_; }

 private:
  /// Measured voxels whose log-odds `counts` accepts.
  std::size_t countMeasured(const std::function<bool(float)>& counts) const;

  /// integrate()'s phases: the occupancy of every voxel the scan touches, then the proximity
  /// marks behind its hits, which read the occupancy just written.
  void applyOccupancy(const ScanUpdate& update, ScanStats& stats);
  void applyProximity(const ScanUpdate& update, ScanStats& stats);

  /// Starts a new revision; later noteChanged() calls belong to it.
  void beginChange();
  /// Records that the block holding `ijk` changed in the current revision.
  void noteChanged(const Index3& ijk);

  Config config_;
  VoxelLattice lattice_;
  std::unique_ptr<Grids> grids_;
  std::uint64_t revision_;
  std::uint64_t history_start_;  ///< changes after this revision are all in the log
  struct BlockChange {
    std::uint64_t revision;
    Index3 block;
  };
  std::vector<BlockChange> change_log_;
};

}  // namespace nbv::grid
