#include "nbv/grid/map_snapshot.hpp"

#include "nbv/errors.hpp"
#include "vdb_grids.hpp"

#include <openvdb/tree/ValueAccessor.h>

#include <algorithm>
#include <bit>
#include <cstring>
#include <limits>
#include <string>

namespace nbv::grid {

namespace {

/// Palette key of a voxel state: measured voxels by their log-odds bits, marked ones by their
/// distance, the unmeasured unmarked voxel 0.
std::uint64_t stateKey(bool measured, float log_odds, std::int32_t mark) {
  if (measured) return (std::uint64_t{1} << 32) | std::bit_cast<std::uint32_t>(log_odds);
  return mark > 0 ? (std::uint64_t{2} << 32) | static_cast<std::uint32_t>(mark) : 0;
}

kernels::VoxelTerms termsOfKey(const kernels::VoxelModel& model, std::uint64_t key) {
  const auto low = static_cast<std::uint32_t>(key);
  switch (key >> 32) {
    case 1: return kernels::voxelTerms(model, true, std::bit_cast<float>(low), 0);
    case 2: return kernels::voxelTerms(model, false, 0.0f, static_cast<std::int32_t>(low));
    default: return kernels::voxelTerms(model, false, 0.0f, 0);
  }
}

/// The snapshot's cap: its voxel entries may take at most `max_bytes`.
void checkBytes(std::size_t bytes, std::size_t max_bytes) {
  if (bytes > max_bytes) {
    throw CapacityError("the IG snapshot of this map needs " + std::to_string(bytes) +
                        " bytes, more than the limit of " + std::to_string(max_bytes));
  }
}

bool sameModel(const kernels::VoxelModel& a, const kernels::VoxelModel& b) {
  return a.occupied_threshold == b.occupied_threshold && a.free_threshold == b.free_threshold &&
         a.proximity_max == b.proximity_max && a.visibility == b.visibility;
}

}  // namespace

std::uint32_t MapSnapshot::stateIndex(bool measured, float log_odds, std::int32_t mark) {
  const std::uint64_t key = stateKey(measured, log_odds, mark);
  const auto [it, added] = state_index_.try_emplace(key, static_cast<std::uint32_t>(states_.size()));
  if (added) {
    if (states_.size() >= kernels::kMaxPaletteSize) {
      state_index_.erase(it);
      throw CapacityError("the map holds more than 2^24 distinct voxel states (log-odds values "
                            "and proximity distances); the IG snapshot cannot index them");
    }
    states_.push_back(key);
    palette_.push_back(termsOfKey(model_, key));
  }
  return it->second;
}

void MapSnapshot::rebuild(const OccupancyMap& map, std::size_t max_bytes) {
  map_ = nullptr;  // until the rebuild completes
  const auto& grids = map.grids();
  openvdb::CoordBBox bounds = grids.log_odds->evalActiveVoxelBoundingBox();
  bounds.expand(grids.proximity->evalActiveVoxelBoundingBox());
  std::fill(size_, size_ + 3, 0u);
  voxels_.clear();
  states_.clear();
  state_index_.clear();
  palette_.clear();
  stateIndex(false, 0.0f, 0);  // entry 0: the prior
  if (bounds.empty()) return;
  const kernels::DenseBox box = kernels::DenseBox::around(toIndex(bounds.min()), toIndex(bounds.max()));
  checkBytes(box.bytes() * sizeof(kernels::SnapshotEntry), max_bytes);
  std::copy(box.min, box.min + 3, min_);
  std::copy(box.size, box.size + 3, size_);
  voxels_.assign(box.bytes(), 0);
  const kernels::SnapshotView v = view();
  // Marks first: a measured voxel overrides (they never coexist in a consistent map).
  for (auto it = grids.proximity->cbeginValueOn(); it; ++it) {
    const std::uint32_t index = stateIndex(false, 0.0f, *it);
    const openvdb::CoordBBox cells = it.getBoundingBox();
    for (auto c = cells.begin(); c; ++c) voxels_[v.offset(toIndex(*c))] = index;
  }
  std::uint64_t last_key = ~std::uint64_t{0};
  std::uint32_t last_index = 0;
  for (auto it = grids.log_odds->cbeginValueOn(); it; ++it) {
    const std::uint64_t key = stateKey(true, *it, 0);
    if (key != last_key) {  // neighbouring voxels often share a state
      last_key = key;
      last_index = stateIndex(true, *it, 0);
    }
    const openvdb::CoordBBox cells = it.getBoundingBox();
    for (auto c = cells.begin(); c; ++c) voxels_[v.offset(toIndex(*c))] = last_index;
  }
  computeDistances(Index3::Zero(), Index3(static_cast<int>(size_[0]) - 1, static_cast<int>(size_[1]) - 1,
                                          static_cast<int>(size_[2]) - 1));
}

namespace {

constexpr auto kCap = static_cast<std::uint8_t>(kernels::kMaxRunDistance);

/// One row of an octant's raster pass (MapSnapshot::computeDistances), sx its sign along x:
/// `distance` the row, `ahead` the distances of the three rows it looks at (one step along y,
/// along z, along both), each padded by a voxel at both ends; `uniform[i - (sx < 0)]` whether
/// voxel i and its 7 neighbours ahead share one palette index.
template <int kSx>
void distanceRow(const std::uint8_t* uniform, const std::uint8_t* const ahead[3], std::uint8_t* __restrict distance,
                 std::size_t row, std::uint8_t* __restrict other) {
  // If they do, the voxel has 1 + the least of the 7 neighbours' distances (capped), else 1.
  // With nearest[i] the least of the six in the rows ahead, lowered to cap - 1, or 0 for "not
  // one index", the row's distances are d[i] = 1 + min(nearest[i], d[i + sx]); this loop
  // leaves 1 + nearest[i] in d[i].
  constexpr std::size_t kBack = kSx < 0 ? 1 : 0;
  const std::uint8_t *const d0 = ahead[0], *const d1 = ahead[1], *const d2 = ahead[2];
  for (std::size_t i = 1; i + 1 < row; ++i) {
    const std::size_t f = i + kSx;
    const std::uint8_t least = std::min(std::min(std::min(d0[i], d0[f]), std::min(d1[i], d1[f])),
                                        std::min(std::min(d2[i], d2[f]), static_cast<std::uint8_t>(kCap - 1)));
    distance[i] = uniform[i - kBack] != 0 ? static_cast<std::uint8_t>(least + 1) : std::uint8_t{1};
  }
  // Unrolled, d[i] = min over j >= 0 of (1 + nearest[i + j sx]) + j, the padding voxel ahead
  // counting with its distance: a minimum over a window that doubles per pass, each pass
  // reading the last one's values from the other buffer (`other`, as long as the row), so that
  // both directions vectorise. Terms with j >= 32 > cap cannot be least: five passes suffice,
  // and a sixth (changing nothing) brings the values back to `distance`.
  static_assert(kernels::kMaxRunDistance < 32);
  std::uint8_t* __restrict from = distance;
  std::uint8_t* __restrict to = other;
  for (std::uint8_t step = 1; step <= 32; step = static_cast<std::uint8_t>(2 * step)) {
    // Voxels within `step` of the padding ahead keep their value (the padding is in their
    // window already).
    if constexpr (kSx > 0) {
      const std::size_t split = row > step ? row - step : 0;
      for (std::size_t i = 0; i < split; ++i) {
        to[i] = std::min(from[i], static_cast<std::uint8_t>(from[i + step] + step));
      }
      std::copy(from + split, from + row, to + split);
    } else {
      const std::size_t split = std::min<std::size_t>(step, row);
      std::copy(from, from + split, to);
      for (std::size_t i = split; i < row; ++i) {
        to[i] = std::min(from[i], static_cast<std::uint8_t>(from[i - step] + step));
      }
    }
    std::swap(from, to);
  }
}

}  // namespace

void MapSnapshot::computeDistances(const Index3& lo, const Index3& hi) {
  // The region and one voxel around it, in scratch arrays padded by that voxel (p: padded
  // sizes): palette indices (0 outside the box) and, per octant, distances (those around the
  // region as they are; outside the box the cap, which can lower nothing). Row by row.
  const int p[3] = {hi.x() - lo.x() + 3, hi.y() - lo.y() + 3, hi.z() - lo.z() + 3};
  const std::size_t row = static_cast<std::size_t>(p[0]), plane = row * static_cast<std::size_t>(p[1]);
  const std::size_t padded = plane * static_cast<std::size_t>(p[2]);
  const auto at = [&](int j, int k) { return static_cast<std::size_t>(k) * plane + static_cast<std::size_t>(j) * row; };
  index_scratch_.resize(padded);
  distance_scratch_.resize(padded * kernels::kOctants);
  std::uint32_t* const index = index_scratch_.data();
  // Octant o's distances of row (j, k) at row_distances(o, j, k): the rows of all octants
  // together, so that a row's padding and its neighbours lie close for every octant.
  const auto row_distances = [&](unsigned o, int j, int k) {
    return distance_scratch_.data() + at(j, k) * kernels::kOctants + o * row;
  };
  const kernels::SnapshotView v = view();
  const Index3 box_min(min_[0], min_[1], min_[2]);
  // Only the padding's distances are read before the passes write them.
  const int x_first = std::max(0, 1 - lo.x()), x_end = std::min(p[0], static_cast<int>(size_[0]) - lo.x() + 1);
  for (int k = 0; k < p[2]; ++k) {
    for (int j = 0; j < p[1]; ++j) {
      const int y = lo.y() + j - 1, z = lo.z() + k - 1;  // box-relative
      const bool row_in_box = y >= 0 && z >= 0 && y < static_cast<int>(size_[1]) && z < static_cast<int>(size_[2]);
      // entries[lo.x() - 1 + i]: the voxel of padded column i (x_first <= i < x_end lie in the box)
      const kernels::SnapshotEntry* const entries =
          row_in_box ? voxels_.data() + v.offset(Index3(0, y, z) + box_min) : nullptr;
      const auto entry = [&](int i) { return entries[lo.x() - 1 + i]; };
      std::uint32_t* const index_row = index + at(j, k);
      const int first = row_in_box ? x_first : p[0], end = row_in_box ? x_end : p[0];
      std::fill(index_row, index_row + first, 0u);
      for (int i = first; i < end; ++i) index_row[i] = kernels::paletteIndex(entry(i));
      std::fill(index_row + std::max(first, end), index_row + p[0], 0u);
      const bool padding_row = j == 0 || k == 0 || j + 1 == p[1] || k + 1 == p[2];
      for (unsigned o = 0; o < kernels::kOctants; ++o) {
        std::uint8_t* const distance_row = row_distances(o, j, k);
        const auto distance = [&](int i) {
          return i >= first && i < end ? static_cast<std::uint8_t>(kernels::runDistance(entry(i), o)) : kCap;
        };
        if (padding_row) {
          for (int i = 0; i < p[0]; ++i) distance_row[i] = distance(i);
        } else {
          distance_row[0] = distance(0);
          distance_row[p[0] - 1] = distance(p[0] - 1);
        }
      }
    }
  }
  // Whether the 2 x 2 x 2 cube with its least corner at each voxel holds one palette index
  // (a voxel with its 7 neighbours ahead in any octant is such a cube); the last layer along
  // each axis has no such cube and is never read.
  uniform_scratch_.resize(padded);
  std::uint8_t* const uniform = uniform_scratch_.data();
  for (int k = 0; k + 1 < p[2]; ++k) {
    for (int j = 0; j + 1 < p[1]; ++j) {
      const std::uint32_t *const r0 = index + at(j, k), *const r1 = index + at(j + 1, k);
      const std::uint32_t *const r2 = index + at(j, k + 1), *const r3 = index + at(j + 1, k + 1);
      std::uint8_t* const u = uniform + at(j, k);
      for (std::size_t i = 0; i + 1 < row; ++i) {  // without a branch, so that it vectorises
        const std::uint32_t mine = r0[i];
        const std::uint32_t other = (r0[i + 1] ^ mine) | (r1[i] ^ mine) | (r1[i + 1] ^ mine) | (r2[i] ^ mine) |
                                    (r2[i + 1] ^ mine) | (r3[i] ^ mine) | (r3[i + 1] ^ mine);
        u[i] = other == 0 ? 1 : 0;
      }
    }
  }
  // Per octant, from the far corner back: a voxel whose 7 neighbours ahead (one step along
  // any non-empty set of the octant's axes) share its index has 1 + the least of their
  // distances (the cube ahead of it is theirs, joined), capped; any other voxel has 1. The two
  // octants that differ only along x go through the rows together.
  std::vector<std::uint8_t> other(row);
  for (unsigned o = 0; o < kernels::kOctants; o += 2) {  // o: x positive, o + 1: x negative
    const int sy = (o & 2) != 0 ? -1 : 1, sz = (o & 4) != 0 ? -1 : 1;
    for (int n = 1; n + 1 < p[2]; ++n) {
      const int k = sz > 0 ? p[2] - 1 - n : n;
      for (int m = 1; m + 1 < p[1]; ++m) {
        const int j = sy > 0 ? p[1] - 1 - m : m;
        const int ahead[3][2] = {{j + sy, k}, {j, k + sz}, {j + sy, k + sz}};
        const std::uint8_t* ahead_forward[3];
        const std::uint8_t* ahead_backward[3];
        for (int r = 0; r < 3; ++r) {
          ahead_forward[r] = row_distances(o, ahead[r][0], ahead[r][1]);
          ahead_backward[r] = row_distances(o + 1, ahead[r][0], ahead[r][1]);
        }
        // The cubes' least corners: one voxel back along each negative axis.
        const std::uint8_t* const cubes = uniform + at(sy > 0 ? j : j - 1, sz > 0 ? k : k - 1);
        distanceRow<1>(cubes, ahead_forward, row_distances(o, j, k), row, other.data());
        distanceRow<-1>(cubes, ahead_backward, row_distances(o + 1, j, k), row, other.data());
      }
    }
  }
  for (int z = lo.z(); z <= hi.z(); ++z) {
    for (int y = lo.y(); y <= hi.y(); ++y) {
      const int j = y - lo.y() + 1, k = z - lo.z() + 1;
      const std::uint32_t* const from = index + at(j, k) + 1;
      kernels::SnapshotEntry* const to = voxels_.data() + v.offset(Index3(lo.x(), y, z) + box_min);
      const std::uint8_t* const distance = row_distances(0, j, k) + 1;  // octant o's: distance[o * row + x]
      for (int x = 0; x <= hi.x() - lo.x(); ++x) {
        kernels::SnapshotEntry e = from[x];
        for (unsigned o = 0; o < kernels::kOctants; ++o) {
          e = kernels::withRunDistance(e, o, distance[o * row + static_cast<std::size_t>(x)]);
        }
        to[x] = e;
      }
    }
  }
}

SnapshotUpdate MapSnapshot::update(const OccupancyMap& map, const kernels::VoxelModel& model,
                                   std::size_t max_bytes) {
  SnapshotUpdate result;
  if (!sameModel(model, model_)) {  // same states, new terms
    model_ = model;
    for (std::size_t i = 0; i < states_.size(); ++i) palette_[i] = termsOfKey(model_, states_[i]);
  }
  std::optional<std::vector<Index3>> blocks;
  if (map_ == &map && !palette_.empty()) blocks = map.changedBlocksSince(revision_);
  // A changed block outside the box means the box must grow.
  const kernels::SnapshotView before = view();
  const bool fits = blocks.has_value() && std::all_of(blocks->begin(), blocks->end(), [&](const Index3& b) {
                      return before.contains(b);
                    });
  if (fits) checkBytes(voxels_.size() * sizeof(kernels::SnapshotEntry), max_bytes);  // a smaller cap than before
  if (!fits) {
    rebuild(map, max_bytes);
    result.rebuilt = true;
    result.blocks = (std::size_t{size_[0]} / 8) * (size_[1] / 8) * (size_[2] / 8);
  } else {
    map_ = nullptr;  // until the refresh completes: a failed one leaves a rebuild for the next update
    const auto& grids = map.grids();
    openvdb::tree::ValueAccessor<const openvdb::FloatTree> log_acc(grids.log_odds->tree());
    openvdb::tree::ValueAccessor<const openvdb::Int32Tree> prox_acc(grids.proximity->tree());
    for (const Index3& block : *blocks) {  // blocks are 8-aligned, as is the box
      for (int dz = 0; dz < 8; ++dz) {
        for (int dy = 0; dy < 8; ++dy) {
          for (int dx = 0; dx < 8; ++dx) {
            const Index3 ijk = block + Index3(dx, dy, dz);
            float log_odds = 0.0f;
            std::int32_t mark = 0;
            const bool measured = log_acc.probeValue(toCoord(ijk), log_odds);
            if (!measured && !prox_acc.probeValue(toCoord(ijk), mark)) mark = 0;
            voxels_[before.offset(ijk)] = stateIndex(measured, log_odds, mark);  // distance: below
          }
        }
      }
    }
    result.blocks = blocks->size();
    if (!blocks->empty()) {  // distances change at most kMaxRunDistance voxels away
      Index3 lo = Index3::Constant(std::numeric_limits<int>::max()), hi = -lo;
      for (const Index3& block : *blocks) {
        lo = lo.cwiseMin(block);
        hi = hi.cwiseMax(block + Index3::Constant(7));
      }
      const Index3 box_min(min_[0], min_[1], min_[2]);
      const Index3 reach = Index3::Constant(static_cast<int>(kernels::kMaxRunDistance) + 1);
      const Index3 last(static_cast<int>(size_[0]) - 1, static_cast<int>(size_[1]) - 1, static_cast<int>(size_[2]) - 1);
      computeDistances((lo - box_min - reach).cwiseMax(Index3::Zero()), (hi - box_min + reach).cwiseMin(last));
    }
  }
  map_ = &map;
  revision_ = map.revision();
  result.palette = palette_.size();
  result.bytes = voxels_.size() * sizeof(kernels::SnapshotEntry) + palette_.size() * sizeof(kernels::VoxelTerms);
  return result;
}

kernels::SnapshotView MapSnapshot::view() const {
  kernels::SnapshotView v;
  std::copy(min_, min_ + 3, v.min);
  std::copy(size_, size_ + 3, v.size);
  v.voxels = voxels_.data();
  v.palette = palette_;
  return v;
}

}  // namespace nbv::grid
