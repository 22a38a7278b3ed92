#pragma once
/// \file The run distances of a MapSnapshot's box (kernels::SnapshotEntry), kept between
/// updates so that a change recomputes only the distances it can change.

#include "nbv/grid/huge_pages.hpp"
#include "nbv/grid/occupancy_map.hpp"
#include "nbv/kernels/ig_rays.hpp"

#include <array>
#include <climits>
#include <cstddef>
#include <cstdint>
#include <vector>

namespace nbv::ig {

using grid::Index3;
using grid::LargeArray;

/// The palette index of every voxel of a box and its run distance in every octant.
///
/// In octant o (signs sx, sy, sz), a voxel's distance is 1 + the least distance of its 7
/// neighbours ahead (one step along any non-empty set of the octant's axes) when the 2 x 2 x 2
/// cube of it and them is uniform (every index the same), capped at kernels::kMaxRunDistance;
/// else 1: kernels::SnapshotEntry's run distance. Outside the box every voxel has index 0 and
/// the cap. So a voxel whose index changes can change the distances of the voxels whose cube
/// holds it (it and the voxels one step behind it), and a changed distance those of the voxels
/// one step behind it, and so on.
///
/// The distances depend on the indices only through the cube flags (uniform or not).
/// update() first redoes the flags of the cubes that hold a changed voxel and
/// keeps the spans of flags that came out different, then visits each octant's rows along x
/// from the octant's far corner (the rows ahead of a row come before it), each over the span
/// of x its changes reach: the voxels whose flag changed (in octant o a voxel's cube is the
/// one whose least corner lies one voxel back along o's negative axes), the unsettled voxels
/// (those next to the old box after a growth), the spans found changed on the rows ahead, and
/// on back along the row while the voxel last recomputed changed (at most the cap behind, the
/// farthest a change travels). A span whose distances come out as before hands nothing on. The
/// octants are independent tasks. Then the entries of the voxels whose index or some distance
/// changed are written.
///
/// Indices, cube flags and distances live in arrays larger than the box (at least a voxel on
/// every side, which reads as outside: index 0, the cap), so that no row needs a bounds check;
/// a box that grew gets room around it, so that growing again usually leaves it where it is.
///
/// Thread-safety: none; a field belongs to one MapSnapshot.
class RunDistanceField {
 public:
  /// An empty box of `size` voxels: every index 0, every voxel to be computed.
  void reset(const std::uint32_t size[3]);

  /// A box of `size` voxels that holds the current box with its first voxel at `offset`
  /// (box-relative, non-negative): the current voxels keep their indices and distances, the
  /// new ones have index 0 and are to be computed.
  void grow(const std::uint32_t size[3], const Index3& offset);

  /// The indices of the row (y, z) of the box (box-relative), x = 0 at [0]. Call changed() for
  /// every voxel whose index is set here.
  std::uint32_t* indexRow(int y, int z) { return index_.data() + at(y, z); }

  /// Marks the box-relative voxels in [lo, hi] (inclusive) as changed: update() recomputes what
  /// their indices reach and writes their entries.
  void changed(const Index3& lo, const Index3& hi) { pending_.push_back({lo, hi}); }

  /// Recomputes every distance the changes since the last update reach, and writes the entry
  /// (index and distances) of every voxel whose index or some distance changed into `entries`
  /// (one per voxel of the box, x fastest). Returns the number of voxels whose entry it wrote.
  std::size_t update(kernels::SnapshotEntry* entries);

  /// Memory held [bytes].
  std::size_t bytes() const { return index_.size() * sizeof(std::uint32_t) + cube_.size() + distance_.size(); }

  /// A span of x along a row, [lo, hi] inclusive; empty when lo > hi.
  struct Span {
    int lo = INT_MAX;
    int hi = INT_MIN;
    bool empty() const { return lo > hi; }
    void unite(int a, int b) {
      lo = lo < a ? lo : a;
      hi = hi > b ? hi : b;
    }
  };

 private:
  struct Region {
    Index3 lo, hi;
  };

  /// Offset in the arrays of box voxel (0, y, z); y and z may lie one voxel outside the box.
  std::size_t at(int y, int z) const {
    return (static_cast<std::size_t>(z + window_[2]) * capacity_[1] + static_cast<std::size_t>(y + window_[1])) *
               capacity_[0] + static_cast<std::size_t>(window_[0]);
  }
  std::size_t capacityVoxels() const { return capacity_[0] * capacity_[1] * capacity_[2]; }
  /// The distances of octant `octant` at array offset `offset`.
  std::uint8_t* distances(unsigned octant, std::size_t offset) {
    return distance_.data() + octant * capacityVoxels() + offset;
  }
  /// Arrays of `capacity` voxels per axis (the memory kept where it has that size already), all
  /// outside: index 0, every cube uniform, the cap. They are written a layer of z per task,
  /// so that their pages are first touched side by side; each task then calls `then(layer)`.
  template <class Then>
  void allocate(const std::size_t capacity[3], const Then& then);
  /// Marks the box-relative voxels in [lo, hi] as unsettled: their distances may break the
  /// rule though no flag of theirs changes (a grown box's voxels next to the old one), so
  /// update() recomputes them whatever their flags.
  void unsettled(const Index3& lo, const Index3& hi) { unsettled_.push_back({lo, hi}); }
  /// Joins the pending regions that continue one another along x (the same rows, adjacent or
  /// overlapping x), so that the passes over them run along longer rows.
  void joinPending();
  /// The cube flags of the cubes holding a voxel of a pending change; the spans of those that
  /// changed go to flag_changes_.
  void updateCubes();
  /// One octant's raster pass over the rows the pending changes reach; leaves the spans whose
  /// distances it changed in computed_[octant].
  void updateOctant(unsigned octant);

  std::uint32_t size_[3] = {0, 0, 0};
  std::size_t capacity_[3] = {0, 0, 0};
  int window_[3] = {1, 1, 1};  ///< where box voxel (0, 0, 0) lies in the arrays
  LargeArray<std::uint32_t> index_;
  /// Per voxel c, whether the cube of c and the voxels one step beyond it along x, y, z is
  /// uniform (1: every index the same) or not (0).
  LargeArray<std::uint8_t> cube_;
  /// Per octant, an array of distances (kernels::kOctants of them, one after another).
  LargeArray<std::uint8_t> distance_;
  std::vector<Region> pending_;  ///< voxels whose indices changed
  std::vector<Region> unsettled_;  ///< voxels recomputed whatever their flags
  /// A span of cube flags that changed in the last updateCubes(): the cubes' least corners on
  /// the row (y, z), box-relative (y and z may be -1).
  struct FlagChange {
    int y, z;
    Span x;
  };
  std::vector<FlagChange> flag_changes_;
  std::vector<Span> written_;  ///< per row (y + size_[1] * z), the voxels whose entries update() writes
  /// Per octant, the span of each row (y + size_[1] * z) whose distances its last pass changed.
  std::array<std::vector<Span>, kernels::kOctants> computed_;
};

}  // namespace nbv::ig
