#pragma once
/// \file A compact dense copy of the part of an OccupancyMap that IG rays can see differ from
/// the prior, kept up to date block by block.

#include "nbv/grid/huge_pages.hpp"
#include "nbv/grid/occupancy_map.hpp"
#include "nbv/kernels/ig_rays.hpp"
#include "nbv/kernels/information_gain.hpp"

#include <cstdint>
#include <unordered_map>
#include <vector>

namespace nbv::grid {

/// What the last MapSnapshot::update() did.
struct SnapshotUpdate {
  bool rebuilt = false;         ///< the whole box was rebuilt (first use, another map, growth)
  std::size_t blocks = 0;       ///< 8^3 blocks rewritten
  std::size_t palette = 0;      ///< distinct voxel states in the snapshot
  std::size_t bytes = 0;        ///< memory held by the snapshot
};

/// One kernels::SnapshotEntry per voxel over the 8-aligned box of the measured and marked
/// voxels: a palette index, the palette holding the kernels::VoxelTerms of each distinct
/// (measured, log-odds, mark) state, entry 0 the unmeasured, unmarked voxel that fills
/// everything else; and the voxel's run distance in each octant (the side of the cube of
/// equal voxels ahead of it), so that rays cross runs of empty voxels without looking at
/// every voxel.
///
/// update() reads only the blocks the map reports changed since the last update, and rebuilds
/// the box when the map is another one, has no history that far back, or outgrew the box.
/// Not thread-safe for update(); view() may be read concurrently between updates.
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
  /// Palette index of a voxel state, adding it if new.
  std::uint32_t stateIndex(bool measured, float log_odds, std::int32_t mark);
  void rebuild(const OccupancyMap& map, std::size_t max_bytes);
  /// Recomputes the run distances of the voxels in [lo, hi] (inclusive, box-relative),
  /// reading those around the region as they are: per octant one raster pass from the far
  /// corner, each voxel 1 + the least distance of its 7 neighbours ahead if they share its
  /// index, else 1 (the largest uniform cube ahead, as the largest square of a 2-D table).
  /// Row by row over a padded copy of the region (index_scratch_; uniform_scratch_: whether
  /// each 2 x 2 x 2 cube holds one index; distance_scratch_: the rows of every octant).
  void computeDistances(const Index3& lo, const Index3& hi);

  const OccupancyMap* map_ = nullptr;  ///< the map of the last update (identity only)
  std::uint64_t revision_ = 0;
  kernels::VoxelModel model_;
  int min_[3] = {0, 0, 0};
  std::uint32_t size_[3] = {0, 0, 0};
  std::vector<kernels::SnapshotEntry, HugePageAllocator<kernels::SnapshotEntry>> voxels_;
  std::vector<std::uint64_t> states_;   ///< palette key per entry
  std::unordered_map<std::uint64_t, std::uint32_t> state_index_;
  std::vector<kernels::VoxelTerms> palette_;
  // computeDistances()'s working copy of the region, kept so that refreshes reuse its memory.
  std::vector<std::uint32_t, HugePageAllocator<std::uint32_t>> index_scratch_;
  std::vector<std::uint8_t, HugePageAllocator<std::uint8_t>> uniform_scratch_;
  std::vector<std::uint8_t, HugePageAllocator<std::uint8_t>> distance_scratch_;
};

}  // namespace nbv::grid
