#pragma once
/// \file A compact dense copy of the part of an OccupancyMap that IG rays can see differ from
/// the prior, kept up to date block by block.

#include "nbv/grid/huge_pages.hpp"
#include "nbv/grid/occupancy_map.hpp"
#include "nbv/kernels/ig_rays.hpp"
#include "nbv/kernels/information_gain.hpp"
#include "nbv/kernels/mark_rays.hpp"
#include "nbv/ig/run_distances.hpp"

#include <cstdint>
#include <unordered_map>
#include <vector>

namespace nbv::ig {

using grid::HugePageAllocator;
using grid::Index3;
using grid::OccupancyMap;

/// What the last MapSnapshot::update() did.
struct SnapshotUpdate {
  bool rebuilt = false;         ///< the whole box was rebuilt (first use, another map, no history)
  bool grown = false;           ///< the box grew to hold changed blocks (what it held was kept)
  std::size_t blocks = 0;       ///< 8^3 blocks read from the map
  std::size_t voxels = 0;       ///< voxel entries rewritten (those whose state or some run distance changed)
  std::size_t palette = 0;      ///< distinct voxel states in the snapshot
  /// The kernels::voxel_flag bits of the palette's states together: a flag missing here is
  /// held by no voxel (a state no voxel holds any more may still add its flags).
  std::uint64_t flags = 0;
  std::size_t bytes = 0;        ///< memory held by the snapshot
};

/// One kernels::SnapshotEntry per voxel over the 8-aligned box of the measured and marked
/// voxels: a palette index, the palette holding the kernels::VoxelTerms of each distinct
/// (measured, log-odds, mark) state, entry 0 the unmeasured, unmarked voxel that fills
/// everything else; and the voxel's run distance in each octant (the side of the cube ahead of
/// it whose voxels share its state), so that rays cross runs of identical voxels without
/// looking at every voxel (SEMANTICS.md "Run skipping").
///
/// update() reads only the blocks the map reports changed since the last update and recomputes
/// the run distances they reach (RunDistanceField); a box the map outgrew grows around what it
/// holds. It rebuilds the box when the map is another one or has no history that far back.
/// Either way the entries equal those of a snapshot built from scratch.
///
/// Thread-safety: update() needs the snapshot to itself; view() may be read concurrently
/// between updates.
class MapSnapshot {
 public:
  /// Brings the snapshot up to `map` under `model`. `max_bytes` caps the voxel entries, also
  /// those of a snapshot already held (a smaller cap than last time is checked again).
  /// \throws CapacityError if the map holds more than 2^24 distinct voxel states, or the box
  /// needs more than `max_bytes`; the next update then rebuilds the snapshot.
  SnapshotUpdate update(const OccupancyMap& map, const kernels::VoxelModel& model,
                        std::size_t max_bytes);

  /// The kernels' view of the snapshot; valid until the next update().
  kernels::SnapshotView view() const;

 private:
  /// Palette index of a voxel state (its key: measured log-odds bits or mark distance), adding
  /// it if new.
  std::uint32_t stateIndex(std::uint64_t key);
  void setBox(const kernels::DenseBox& box);
  /// The whole box from the map: palette, indices, distances.
  void rebuild(const OccupancyMap& map, std::size_t max_bytes);
  /// Room for at least `voxels` entries, and for a box grown by half, within `max_bytes`.
  void reserveRoom(std::size_t voxels, std::size_t max_bytes);
  /// The box `box`, which holds the current one: the entries kept, the new voxels prior.
  void grow(const kernels::DenseBox& box, std::size_t max_bytes);
  /// The indices of the voxels of `blocks` (8-aligned, in the box) from the map, marked changed.
  void readBlocks(const OccupancyMap& map, const std::vector<Index3>& blocks);
  /// Under VoxelModel::frontier: the frontier bit of every voxel of the box-relative region
  /// [lo, hi] (clamped to the box) set from its neighbours' classes, the voxels whose index
  /// changed marked changed.
  void flagFrontier(Index3 lo, Index3 hi);

  const OccupancyMap* map_ = nullptr;  ///< the map of the last update (identity only)
  std::uint64_t revision_ = 0;
  kernels::VoxelModel model_;
  int min_[3] = {0, 0, 0};
  std::uint32_t size_[3] = {0, 0, 0};
  std::vector<kernels::SnapshotEntry, HugePageAllocator<kernels::SnapshotEntry>> voxels_;
  std::vector<std::uint64_t> states_;   ///< palette key per entry
  std::unordered_map<std::uint64_t, std::uint32_t> state_index_;
  std::vector<kernels::VoxelTerms> palette_;
  RunDistanceField distances_;  ///< the box's indices and run distances, padded
};

}  // namespace nbv::ig
