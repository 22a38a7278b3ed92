#include "nbv/grid/map_snapshot.hpp"

#include "nbv/grid/errors.hpp"
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
  if (box.bytes() * sizeof(kernels::SnapshotEntry) > max_bytes) {
    throw CapacityError("the IG snapshot of this map needs " +
                          std::to_string(box.bytes() * sizeof(kernels::SnapshotEntry)) +
                          " bytes, more than the limit of " + std::to_string(max_bytes));
  }
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

void MapSnapshot::computeDistances(const Index3& lo, const Index3& hi) {
  // The region and one voxel around it, in scratch arrays padded by that voxel (p: padded
  // sizes): palette indices (0 outside the box) and distances (those around the region as
  // they are; outside the box the cap, which can lower nothing). Row by row, so that every
  // loop but the one along x of each chamfer pass runs over contiguous rows.
  const int p[3] = {hi.x() - lo.x() + 3, hi.y() - lo.y() + 3, hi.z() - lo.z() + 3};
  const std::size_t row = static_cast<std::size_t>(p[0]), plane = row * static_cast<std::size_t>(p[1]);
  const auto at = [&](int j, int k) { return static_cast<std::size_t>(k) * plane + static_cast<std::size_t>(j) * row; };
  index_scratch_.resize(plane * static_cast<std::size_t>(p[2]));
  distance_scratch_.resize(index_scratch_.size());
  std::uint32_t* const index = index_scratch_.data();
  std::uint8_t* const distance = distance_scratch_.data();
  constexpr auto kCap = static_cast<std::uint8_t>(kernels::kMaxRunDistance);
  const kernels::SnapshotView v = view();
  for (int k = 0; k < p[2]; ++k) {
    for (int j = 0; j < p[1]; ++j) {
      for (int i = 0; i < p[0]; ++i) {
        const Index3 ijk = lo + Index3(i - 1, j - 1, k - 1);  // box-relative
        const bool in_box = ijk.x() >= 0 && ijk.y() >= 0 && ijk.z() >= 0 && ijk.x() < static_cast<int>(size_[0]) &&
                            ijk.y() < static_cast<int>(size_[1]) && ijk.z() < static_cast<int>(size_[2]);
        const kernels::SnapshotEntry e = in_box ? voxels_[v.offset(ijk + Index3(min_[0], min_[1], min_[2]))] : 0;
        index[at(j, k) + static_cast<std::size_t>(i)] = kernels::paletteIndex(e);
        distance[at(j, k) + static_cast<std::size_t>(i)] = in_box ? static_cast<std::uint8_t>(kernels::runDistance(e)) : kCap;
      }
    }
  }
  // Distance 1 next to another palette index, else the cap: a voxel's 3x3x3 neighbourhood
  // (itself included) holds another index exactly when its largest and smallest differ.
  std::vector<std::uint32_t> largest(row), smallest(row);
  for (int k = 1; k + 1 < p[2]; ++k) {
    for (int j = 1; j + 1 < p[1]; ++j) {
      std::copy_n(index + at(j, k), row, largest.begin());
      std::copy_n(index + at(j, k), row, smallest.begin());
      for (int dk = -1; dk <= 1; ++dk) {
        for (int dj = -1; dj <= 1; ++dj) {
          const std::uint32_t* const other = index + at(j + dj, k + dk);
          for (std::size_t i = 0; i < row; ++i) {
            largest[i] = std::max(largest[i], other[i]);
            smallest[i] = std::min(smallest[i], other[i]);
          }
        }
      }
      std::uint8_t* const d = distance + at(j, k);
      for (std::size_t i = 1; i + 1 < row; ++i) {
        const std::uint32_t most = std::max(std::max(largest[i - 1], largest[i]), largest[i + 1]);
        const std::uint32_t least = std::min(std::min(smallest[i - 1], smallest[i]), smallest[i + 1]);
        d[i] = most != least ? 1 : kCap;
      }
    }
  }
  // Two raster passes of the 3x3x3 chamfer: every voxel takes 1 + the smallest distance among
  // its 13 neighbours before it in the pass's order (all its neighbours share its index when
  // its distance is above 1): the 12 in the rows before (the plane before and the row before
  // in this plane), then the one before it in its own row, already updated.
  std::vector<std::uint8_t> before(row);
  auto pass = [&](bool forward) {
    const int s = forward ? -1 : 1;  // where "before" lies
    for (int n = 1; n + 1 < p[2]; ++n) {
      const int k = forward ? n : p[2] - 1 - n;
      for (int m = 1; m + 1 < p[1]; ++m) {
        const int j = forward ? m : p[1] - 1 - m;
        const std::uint8_t* const r0 = distance + at(j - 1, k + s);
        const std::uint8_t* const r1 = distance + at(j, k + s);
        const std::uint8_t* const r2 = distance + at(j + 1, k + s);
        const std::uint8_t* const r3 = distance + at(j + s, k);
        for (std::size_t i = 0; i < row; ++i) before[i] = std::min(std::min(r0[i], r1[i]), std::min(r2[i], r3[i]));
        std::uint8_t* const d = distance + at(j, k);
        for (std::size_t i = 1; i + 1 < row; ++i) {
          const std::uint8_t near = std::min(std::min(before[i - 1], before[i]), before[i + 1]);
          d[i] = std::min<std::uint8_t>(d[i], static_cast<std::uint8_t>(near + 1));
        }
        if (forward) {
          for (std::size_t i = 1; i + 1 < row; ++i) d[i] = std::min<std::uint8_t>(d[i], static_cast<std::uint8_t>(d[i - 1] + 1));
        } else {
          for (std::size_t i = row - 2; i >= 1; --i) d[i] = std::min<std::uint8_t>(d[i], static_cast<std::uint8_t>(d[i + 1] + 1));
        }
      }
    }
  };
  pass(true);
  pass(false);
  for (int z = lo.z(); z <= hi.z(); ++z) {
    for (int y = lo.y(); y <= hi.y(); ++y) {
      const std::size_t from = at(y - lo.y() + 1, z - lo.z() + 1) + 1;
      kernels::SnapshotEntry* const to = voxels_.data() + v.offset(Index3(lo.x() + min_[0], y + min_[1], z + min_[2]));
      for (int x = 0; x <= hi.x() - lo.x(); ++x) {
        to[x] = kernels::makeEntry(index[from + static_cast<std::size_t>(x)], distance[from + static_cast<std::size_t>(x)]);
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
  if (!fits) {
    rebuild(map, max_bytes);
    result.rebuilt = true;
    result.blocks = (std::size_t{size_[0]} / 8) * (size_[1] / 8) * (size_[2] / 8);
  } else {
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
