#include "nbv/ig/map_snapshot.hpp"

#include "nbv/errors.hpp"
#include "nbv/fork_join.hpp"
#include "vdb_grids.hpp"

#include <openvdb/tree/ValueAccessor.h>

#include <algorithm>
#include <array>
#include <bit>
#include <cstring>
#include <limits>
#include <optional>
#include <string>

namespace nbv::ig {

using grid::toCoord;
using grid::toIndex;

namespace {

/// The bit of a palette key that flags a frontier voxel (an unknown voxel with a free face
/// neighbour), set only under VoxelModel::frontier.
constexpr std::uint64_t kFrontierKey = std::uint64_t{1} << 40;

/// Palette key of a voxel state: measured voxels by their log-odds bits, marked ones by their
/// distance, the unmeasured unmarked voxel 0.
std::uint64_t stateKey(bool measured, float log_odds, std::int32_t mark) {
  if (measured) return (std::uint64_t{1} << 32) | std::bit_cast<std::uint32_t>(log_odds);
  return mark > 0 ? (std::uint64_t{2} << 32) | static_cast<std::uint32_t>(mark) : 0;
}

kernels::VoxelTerms termsOfKey(const kernels::VoxelModel& model, std::uint64_t key) {
  const auto low = static_cast<std::uint32_t>(key);
  kernels::VoxelTerms terms;
  switch ((key & ~kFrontierKey) >> 32) {
    case 1: terms = kernels::voxelTerms(model, true, std::bit_cast<float>(low), 0); break;
    case 2: terms = kernels::voxelTerms(model, false, 0.0f, static_cast<std::int32_t>(low)); break;
    default: terms = kernels::voxelTerms(model, false, 0.0f, 0); break;
  }
  if ((key & kFrontierKey) != 0) terms.flags |= kernels::voxel_flag::kFrontier;
  return terms;
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
         a.proximity_max == b.proximity_max && a.visibility == b.visibility && a.frontier == b.frontier;
}

}  // namespace

std::uint32_t MapSnapshot::stateIndex(std::uint64_t key) {
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

namespace {

/// The 8-aligned box of a map's measured and marked voxels, with `margin` voxels around them
/// (1 under VoxelModel::frontier: the unknown neighbours of a free voxel); false if it has none.
bool boxOf(const OccupancyMap& map, int margin, kernels::DenseBox& box) {
  const auto& grids = map.grids();
  openvdb::CoordBBox bounds = grids.log_odds->evalActiveVoxelBoundingBox();
  bounds.expand(grids.proximity->evalActiveVoxelBoundingBox());
  if (bounds.empty()) return false;
  bounds.expand(margin);
  box = kernels::DenseBox::around(toIndex(bounds.min()), toIndex(bounds.max()));
  return true;
}

/// Whether `outer` holds every voxel of `inner`.
bool holds(const kernels::DenseBox& outer, const kernels::SnapshotView& inner) {
  for (int a = 0; a < 3; ++a) {
    const std::int64_t outer_end = std::int64_t{outer.min[a]} + outer.size[a];
    if (outer.min[a] > inner.min[a] || outer_end < std::int64_t{inner.min[a]} + inner.size[a]) return false;
  }
  return true;
}

/// The palette keys (stateKey()) of one 8^3 block's voxels: a leaf's values and active flags
/// read in place; a voxel of a block without a leaf lies in a tile (or nowhere), and the tree
/// is asked. The accessors belong to the caller's thread.
class BlockKeys {
 public:
  using LogLeaf = grid::LogOddsTree::LeafNodeType;
  using MarkLeaf = grid::MarkTree::LeafNodeType;
  static_assert(LogLeaf::DIM == 8 && MarkLeaf::DIM == 8, "a block is one leaf of each grid");

  BlockKeys(openvdb::tree::ValueAccessor<const grid::LogOddsTree>& log_acc,
            openvdb::tree::ValueAccessor<const grid::MarkTree>& mark_acc, const Index3& block)
      : log_acc_(log_acc), mark_acc_(mark_acc), block_(block),
        log_leaf_(log_acc.probeConstLeaf(toCoord(block))), mark_leaf_(mark_acc.probeConstLeaf(toCoord(block))),
        log_values_(log_leaf_ != nullptr ? log_leaf_->buffer().data() : nullptr),
        mark_values_(mark_leaf_ != nullptr ? mark_leaf_->buffer().data() : nullptr) {}

  /// The key of the block's voxel (dx, dy, dz).
  std::uint64_t operator()(int dx, int dy, int dz) const {
    const openvdb::Index n = LogLeaf::coordToOffset(openvdb::Coord(dx, dy, dz));
    const openvdb::Coord c = toCoord(block_ + Index3(dx, dy, dz));
    float log_odds = 0.0f;
    const bool measured = log_leaf_ != nullptr ? log_leaf_->valueMask().isOn(n) : log_acc_.probeValue(c, log_odds);
    if (measured) return stateKey(true, log_leaf_ != nullptr ? log_values_[n] : log_odds, 0);
    grid::MarkTree::ValueType mark = 0;
    if (mark_leaf_ != nullptr) return stateKey(false, 0.0f, mark_leaf_->valueMask().isOn(n) ? mark_values_[n] : 0);
    return stateKey(false, 0.0f, mark_acc_.probeValue(c, mark) ? mark : 0);
  }

 private:
  openvdb::tree::ValueAccessor<const grid::LogOddsTree>& log_acc_;
  openvdb::tree::ValueAccessor<const grid::MarkTree>& mark_acc_;
  Index3 block_;
  const LogLeaf* log_leaf_;
  const MarkLeaf* mark_leaf_;
  const float* log_values_;
  const grid::MarkTree::ValueType* mark_values_;
};

}  // namespace

void MapSnapshot::setBox(const kernels::DenseBox& box) {
  std::copy(box.min, box.min + 3, min_);
  std::copy(box.size, box.size + 3, size_);
}

void MapSnapshot::rebuild(const OccupancyMap& map, std::size_t max_bytes) {
  states_.clear();
  state_index_.clear();
  palette_.clear();
  stateIndex(stateKey(false, 0.0f, 0));  // entry 0: the prior
  kernels::DenseBox box;
  if (!boxOf(map, model_.frontier ? 1 : 0, box)) box = kernels::DenseBox{};
  checkBytes(box.bytes() * sizeof(kernels::SnapshotEntry), max_bytes);
  reserveRoom(box.bytes(), max_bytes);
  voxels_.assign(box.bytes(), 0);
  setBox(box);
  distances_.reset(size_);
  const auto& grids = map.grids();
  const Index3 box_min(min_[0], min_[1], min_[2]);
  const auto set = [&](const openvdb::CoordBBox& cells, std::uint32_t index) {
    for (auto c = cells.begin(); c; ++c) {
      const Index3 r = toIndex(*c) - box_min;
      distances_.indexRow(r.y(), r.z())[r.x()] = index;
    }
  };
  // Marks first: a measured voxel overrides (they never coexist in a consistent map).
  for (auto it = grids.proximity->cbeginValueOn(); it; ++it) set(it.getBoundingBox(), stateIndex(stateKey(false, 0.0f, *it)));
  std::uint64_t last_key = ~std::uint64_t{0};
  std::uint32_t last_index = 0;
  for (auto it = grids.log_odds->cbeginValueOn(); it; ++it) {
    const std::uint64_t key = stateKey(true, *it, 0);
    if (key != last_key) {  // neighbouring voxels often share a state
      last_key = key;
      last_index = stateIndex(key);
    }
    set(it.getBoundingBox(), last_index);
  }
  if (model_.frontier) flagFrontier(Index3::Zero(), Index3(size_[0], size_[1], size_[2]) - Index3::Ones());
}

void MapSnapshot::flagFrontier(Index3 lo, Index3 hi) {
  const Index3 last(static_cast<int>(size_[0]) - 1, static_cast<int>(size_[1]) - 1, static_cast<int>(size_[2]) - 1);
  if ((last.array() < 0).any()) return;  // an empty box
  lo = lo.cwiseMax(Index3::Zero());
  hi = hi.cwiseMin(last);
  if ((lo.array() > hi.array()).any()) return;
  Index3 changed_lo = hi, changed_hi = lo;
  bool changed = false;
  // Sets voxel r's key (in place) to its key with the frontier bit as `frontier` says.
  const auto flag = [&](const Index3& r, bool frontier) {
    std::uint32_t& index = distances_.indexRow(r.y(), r.z())[r.x()];
    const std::uint64_t key = (states_[index] & ~kFrontierKey) | (frontier ? kFrontierKey : 0);
    if (key == states_[index]) return;
    index = stateIndex(key);
    changed_lo = changed_lo.cwiseMin(r);
    changed_hi = changed_hi.cwiseMax(r);
    changed = true;
  };
  // A voxel's flag: unknown, and a face neighbour free (a neighbour outside the box is prior:
  // the box has a voxel of margin around every free voxel). The classes do not depend on the
  // flags, so the region's voxels read their neighbours' classes in any order.
  const auto free_at = [&](Index3 n, int axis, int step) {
    n[axis] += step;
    if (n[axis] < 0 || n[axis] > last[axis]) return false;
    return (palette_[distances_.indexRow(n.y(), n.z())[n.x()]].flags & kernels::voxel_flag::kFree) != 0;
  };
  for (int z = lo.z(); z <= hi.z(); ++z) {
    for (int y = lo.y(); y <= hi.y(); ++y) {
      const std::uint32_t* row = distances_.indexRow(y, z);
      for (int x = lo.x(); x <= hi.x(); ++x) {
        const Index3 r(x, y, z);
        bool frontier = false;
        if ((palette_[row[x]].flags & kernels::voxel_flag::kUnknown) != 0) {
          for (int a = 0; a < 3 && !frontier; ++a) frontier = free_at(r, a, -1) || free_at(r, a, 1);
        }
        if (frontier != ((states_[row[x]] & kFrontierKey) != 0)) flag(r, frontier);
      }
    }
  }
  if (changed) distances_.changed(changed_lo, changed_hi);
}

void MapSnapshot::reserveRoom(std::size_t voxels, std::size_t max_bytes) {
  // Half as much again, within the cap: memory reserved but not yet written costs no page
  // faults, and a box that grows into it keeps its entries where they are instead of copying
  // them to a new block.
  if (voxels > voxels_.capacity()) {
    voxels_.reserve(std::max(voxels, std::min(voxels + voxels / 2, max_bytes / sizeof(kernels::SnapshotEntry))));
  }
}

void MapSnapshot::grow(const kernels::DenseBox& box, std::size_t max_bytes) {
  checkBytes(box.bytes() * sizeof(kernels::SnapshotEntry), max_bytes);
  const std::size_t voxels = box.bytes();
  reserveRoom(voxels, max_bytes);
  voxels_.resize(voxels);
  // The rows in place: each moves to an offset at least its own, so going from the last row
  // back none overwrites a row not yet moved. The new voxels' entries are written when their
  // distances are computed.
  const Index3 offset(min_[0] - box.min[0], min_[1] - box.min[1], min_[2] - box.min[2]);
  for (std::uint32_t z = size_[2]; z-- > 0;) {
    for (std::uint32_t y = size_[1]; y-- > 0;) {
      const std::size_t from = (std::size_t{z} * size_[1] + y) * size_[0];
      const std::size_t to = ((std::size_t{z} + static_cast<std::size_t>(offset.z())) * box.size[1] + y +
                              static_cast<std::size_t>(offset.y())) * box.size[0] + static_cast<std::size_t>(offset.x());
      std::memmove(voxels_.data() + to, voxels_.data() + from, size_[0] * sizeof(kernels::SnapshotEntry));
    }
  }
  setBox(box);
  distances_.grow(size_, offset);
}

void MapSnapshot::readBlocks(const OccupancyMap& map, const std::vector<Index3>& blocks) {
  const auto& grids = map.grids();
  const Index3 box_min(min_[0], min_[1], min_[2]);
  const bool frontier = model_.frontier;
  // Tasks of kBlocksPerTask blocks read their voxels side by side and look their states up in
  // the palette, which only the serial pass below adds to. A state the palette lacks leaves
  // kUnknown and goes to its task's list; those lists, in block order, then add the new states
  // in the order a single pass over the blocks meets them, so the palette is the same. Each
  // block keeps the box of its voxels whose index changed: only those can change a cube flag
  // or need their entry written (a scan's rays cross only some voxels of a block they reach,
  // and a voxel at a clamping bound keeps its state).
  constexpr std::size_t kBlocksPerTask = 16;
  constexpr std::uint32_t kUnknown = ~std::uint32_t{0};
  struct Unknown {
    std::uint32_t* index;
    std::uint64_t key;
  };
  const std::size_t tasks = (blocks.size() + kBlocksPerTask - 1) / kBlocksPerTask;
  std::vector<std::vector<Unknown>> unknown(tasks);
  std::vector<std::pair<Index3, Index3>> moved(blocks.size());  // per block: least and greatest corner
  const auto read = [&](std::size_t task) {
    openvdb::tree::ValueAccessor<const grid::LogOddsTree> log_acc(grids.log_odds->tree());
    openvdb::tree::ValueAccessor<const grid::MarkTree> mark_acc(grids.proximity->tree());
    // The states met lately, by a hash of their key, in front of the palette's map.
    constexpr int kRecentBits = 6;
    std::array<std::pair<std::uint64_t, std::uint32_t>, std::size_t{1} << kRecentBits> recent;
    recent.fill({~std::uint64_t{0}, kUnknown});
    const std::size_t end = std::min(blocks.size(), (task + 1) * kBlocksPerTask);
    for (std::size_t b = task * kBlocksPerTask; b < end; ++b) {  // 8-aligned, as is the box
      const BlockKeys key_of(log_acc, mark_acc, blocks[b]);
      const Index3 r = blocks[b] - box_min;
      Index3 lo = Index3::Constant(8), hi = Index3::Constant(-1);
      for (int dz = 0; dz < 8; ++dz) {
        for (int dy = 0; dy < 8; ++dy) {
          std::uint32_t* const row = distances_.indexRow(r.y() + dy, r.z() + dz) + r.x();
          unsigned moved_x = 0;  // bit dx: the voxel's index changed
          for (int dx = 0; dx < 8; ++dx) {
            const std::uint64_t key = key_of(dx, dy, dz);
            // A voxel whose state is the same keeps its entry, its frontier flag included
            // (flagFrontier() sets the flags the change reaches afterwards).
            if (frontier && (states_[row[dx]] & ~kFrontierKey) == key) continue;
            auto& [recent_key, index] = recent[(key * 0x9E3779B97F4A7C15ull) >> (64 - kRecentBits)];
            if (recent_key != key) {
              const auto known = state_index_.find(key);
              recent_key = key;
              index = known != state_index_.end() ? known->second : kUnknown;
            }
            if (index == kUnknown) unknown[task].push_back({row + dx, key});
            moved_x |= (row[dx] != index ? 1u : 0u) << dx;
            row[dx] = index;
          }
          if (moved_x != 0) {
            lo = lo.cwiseMin(Index3(std::countr_zero(moved_x), dy, dz));
            hi = hi.cwiseMax(Index3(std::bit_width(moved_x) - 1, dy, dz));
          }
        }
      }
      moved[b] = {lo, hi};
    }
  };
  ForkJoin::parallelFor(tasks, read);
  for (const std::vector<Unknown>& list : unknown) {
    for (const Unknown& u : list) *u.index = stateIndex(u.key);
  }
  for (std::size_t b = 0; b < blocks.size(); ++b) {
    const auto& [lo, hi] = moved[b];
    if (hi.x() < 0) continue;  // every index as it was
    const Index3 r = blocks[b] - box_min;
    distances_.changed(r + lo, r + hi);
  }
}

SnapshotUpdate MapSnapshot::update(const OccupancyMap& map, const kernels::VoxelModel& model,
                                   std::size_t max_bytes) {
  SnapshotUpdate result;
  const bool frontier_changed = model.frontier != model_.frontier;  // other keys: a rebuild
  if (!sameModel(model, model_)) {  // same states, new terms
    model_ = model;
    for (std::size_t i = 0; i < states_.size(); ++i) palette_[i] = termsOfKey(model_, states_[i]);
  }
  std::optional<std::vector<Index3>> blocks;
  if (map_ == &map && !palette_.empty() && !frontier_changed) blocks = map.changedBlocksSince(revision_);
  map_ = nullptr;  // until the update completes: a failed one leaves a rebuild for the next
  const kernels::SnapshotView before = view();
  // Frontier flags reach one voxel past a changed block: that voxel must be in the box too.
  const int margin = model_.frontier ? 1 : 0;
  const bool fits = blocks.has_value() && std::all_of(blocks->begin(), blocks->end(), [&](const Index3& b) {
                      return before.contains(b - Index3::Constant(margin)) && before.contains(b + Index3::Constant(7 + margin));
                    });
  // A changed block outside the box: the box grows to the map's, keeping what it holds.
  kernels::DenseBox box;
  const bool grows =
      blocks.has_value() && !fits && before.size[0] > 0 && boxOf(map, margin, box) && holds(box, before);
  if (fits || grows) {
    if (grows) {
      grow(box, max_bytes);
      result.grown = true;
    } else {
      checkBytes(voxels_.size() * sizeof(kernels::SnapshotEntry), max_bytes);  // a smaller cap than before
    }
    readBlocks(map, *blocks);
    if (model_.frontier) {
      const Index3 box_min(min_[0], min_[1], min_[2]);
      for (const Index3& b : *blocks) flagFrontier(b - box_min - Index3::Ones(), b - box_min + Index3::Constant(8));
    }
    result.blocks = blocks->size();
  } else {
    rebuild(map, max_bytes);
    result.rebuilt = true;
    result.blocks = (std::size_t{size_[0]} / 8) * (size_[1] / 8) * (size_[2] / 8);
  }
  result.voxels = distances_.update(voxels_.data());
  map_ = &map;
  revision_ = map.revision();
  result.palette = palette_.size();
  for (const kernels::VoxelTerms& terms : palette_) result.flags |= terms.flags;
  result.bytes = voxels_.size() * sizeof(kernels::SnapshotEntry) + palette_.size() * sizeof(kernels::VoxelTerms) +
                 distances_.bytes();
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

}  // namespace nbv::ig
