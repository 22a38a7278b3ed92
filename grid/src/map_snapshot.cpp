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
  using kernels::paletteIndex;
  using kernels::runDistance;
  const int size[3] = {static_cast<int>(size_[0]), static_cast<int>(size_[1]), static_cast<int>(size_[2])};
  const std::ptrdiff_t stride[3] = {1, static_cast<std::ptrdiff_t>(size_[0]),
                                    static_cast<std::ptrdiff_t>(size_[0]) * static_cast<std::ptrdiff_t>(size_[1])};
  // The 26 neighbours; the first 13 come before a voxel in raster order.
  struct Neighbour {
    int dx, dy, dz;
    std::ptrdiff_t delta;
  };
  std::vector<Neighbour> neighbours;
  for (int dz = -1; dz <= 1; ++dz) {
    for (int dy = -1; dy <= 1; ++dy) {
      for (int dx = -1; dx <= 1; ++dx) {
        if (dx != 0 || dy != 0 || dz != 0) neighbours.push_back({dx, dy, dz, dx * stride[0] + dy * stride[1] + dz * stride[2]});
      }
    }
  }
  kernels::SnapshotEntry* const voxels = voxels_.data();
  // Calls visit(neighbour_or_null) for the given neighbours of voxel (x, y, z); null for one
  // outside the box. Interior voxels skip the bounds checks.
  auto forNeighbours = [&](int x, int y, int z, std::size_t first, std::size_t count, auto&& visit) {
    kernels::SnapshotEntry* const at = voxels + x * stride[0] + y * stride[1] + z * stride[2];
    const bool interior = x > 0 && y > 0 && z > 0 && x + 1 < size[0] && y + 1 < size[1] && z + 1 < size[2];
    for (std::size_t n = first; n < first + count; ++n) {
      const Neighbour& nb = neighbours[n];
      if (interior || (x + nb.dx >= 0 && y + nb.dy >= 0 && z + nb.dz >= 0 && x + nb.dx < size[0] &&
                       y + nb.dy < size[1] && z + nb.dz < size[2])) {
        visit(at + nb.delta);
      } else {
        visit(nullptr);
      }
    }
  };
  // Distance 1 next to another palette index (outside the box: index 0), else the cap.
  for (int z = lo.z(); z <= hi.z(); ++z) {
    for (int y = lo.y(); y <= hi.y(); ++y) {
      for (int x = lo.x(); x <= hi.x(); ++x) {
        kernels::SnapshotEntry& e = voxels[x * stride[0] + y * stride[1] + z * stride[2]];
        const std::uint32_t index = paletteIndex(e);
        bool edge = false;
        forNeighbours(x, y, z, 0, neighbours.size(), [&](const kernels::SnapshotEntry* n) {
          edge = edge || (n != nullptr ? paletteIndex(*n) : 0u) != index;
        });
        e = kernels::makeEntry(index, edge ? 1 : kernels::kMaxRunDistance);
      }
    }
  }
  // Then every voxel takes 1 + the smallest distance among the 13 neighbours the raster order
  // has already visited (forward: the first 13, backward: the last 13); all its neighbours
  // share its index when its distance is above 1.
  auto pass = [&](bool forward) {
    const int step = forward ? 1 : -1;
    const int z0 = forward ? lo.z() : hi.z(), z1 = forward ? hi.z() + 1 : lo.z() - 1;
    const int y0 = forward ? lo.y() : hi.y(), y1 = forward ? hi.y() + 1 : lo.y() - 1;
    const int x0 = forward ? lo.x() : hi.x(), x1 = forward ? hi.x() + 1 : lo.x() - 1;
    for (int z = z0; z != z1; z += step) {
      for (int y = y0; y != y1; y += step) {
        for (int x = x0; x != x1; x += step) {
          kernels::SnapshotEntry& e = voxels[x * stride[0] + y * stride[1] + z * stride[2]];
          unsigned d = runDistance(e);
          if (d <= 1) continue;
          forNeighbours(x, y, z, forward ? 0 : 13, 13, [&](const kernels::SnapshotEntry* n) {
            if (n != nullptr) d = std::min(d, runDistance(*n) + 1);
          });
          e = kernels::makeEntry(paletteIndex(e), d);
        }
      }
    }
  };
  pass(true);
  pass(false);
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
