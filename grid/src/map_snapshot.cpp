#include "nbv/grid/map_snapshot.hpp"

#include "nbv/grid/errors.hpp"
#include "vdb_grids.hpp"

#include <openvdb/tree/ValueAccessor.h>

#include <algorithm>
#include <bit>
#include <cstring>
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

std::uint16_t MapSnapshot::stateIndex(bool measured, float log_odds, std::int32_t mark) {
  const std::uint64_t key = stateKey(measured, log_odds, mark);
  const auto [it, added] = state_index_.try_emplace(key, static_cast<std::uint16_t>(states_.size()));
  if (added) {
    if (states_.size() > 0xFFFF) {
      state_index_.erase(it);
      throw InvalidArgument("the map holds more than 65,535 distinct voxel states (log-odds values "
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
  voxels_.assign(kernels::kSnapshotPadding, 0);
  states_.clear();
  state_index_.clear();
  palette_.clear();
  stateIndex(false, 0.0f, 0);  // entry 0: the prior
  if (bounds.empty()) return;
  const kernels::DenseBox box = kernels::DenseBox::around(toIndex(bounds.min()), toIndex(bounds.max()));
  if (box.bytes() * sizeof(std::uint16_t) > max_bytes) {
    throw InvalidArgument("the IG snapshot of this map needs " + std::to_string(box.bytes() * 2) +
                          " bytes, more than the limit of " + std::to_string(max_bytes));
  }
  std::copy(box.min, box.min + 3, min_);
  std::copy(box.size, box.size + 3, size_);
  voxels_.assign(box.bytes() + kernels::kSnapshotPadding, 0);
  const kernels::SnapshotView v = view();
  // Marks first: a measured voxel overrides (they never coexist in a consistent map).
  for (auto it = grids.proximity->cbeginValueOn(); it; ++it) {
    const std::uint16_t index = stateIndex(false, 0.0f, *it);
    const openvdb::CoordBBox cells = it.getBoundingBox();
    for (auto c = cells.begin(); c; ++c) voxels_[v.offset(toIndex(*c))] = index;
  }
  std::uint64_t last_key = ~std::uint64_t{0};
  std::uint16_t last_index = 0;
  for (auto it = grids.log_odds->cbeginValueOn(); it; ++it) {
    const std::uint64_t key = stateKey(true, *it, 0);
    if (key != last_key) {  // neighbouring voxels often share a state
      last_key = key;
      last_index = stateIndex(true, *it, 0);
    }
    const openvdb::CoordBBox cells = it.getBoundingBox();
    for (auto c = cells.begin(); c; ++c) voxels_[v.offset(toIndex(*c))] = last_index;
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
            voxels_[before.offset(ijk)] = stateIndex(measured, log_odds, mark);
          }
        }
      }
    }
    result.blocks = blocks->size();
  }
  map_ = &map;
  revision_ = map.revision();
  result.palette = palette_.size();
  result.bytes = voxels_.size() * sizeof(std::uint16_t) + palette_.size() * sizeof(kernels::VoxelTerms);
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
