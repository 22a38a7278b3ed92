#include "nbv/ig/run_distances.hpp"

#include "nbv/fork_join.hpp"

#ifdef __SSE2__
#include <emmintrin.h>
#endif

#include <algorithm>
#include <bit>
#include <climits>
#include <cstring>
#include <type_traits>
#include <tuple>
#include <utility>

namespace nbv::ig {

namespace {

constexpr auto kCap = static_cast<std::uint8_t>(kernels::kMaxRunDistance);

/// What a row's distances read in one octant, each pointer at the row's voxel x = 0: the flags
/// of the voxels' cubes (a voxel's cube: it and its 7 neighbours ahead; 1 when their indices are
/// equal), and the distances of
/// the three rows one step ahead along y, along z and along both.
struct RowInputs {
  const std::uint8_t* cube;
  const std::uint8_t* ahead[3];
};

/// A row's distances in an octant whose step along x is kSx (+1 or -1), `distance` at x = 0 (the
/// voxels just outside the row readable): recomputed over [lo, hi] and on along the row
/// backwards (against kSx) while the voxel last computed changed, for it changes the one behind
/// it; no further than the cap behind [lo, hi], the farthest a change travels. A voxel's
/// distance is 1 + min(the least of the 6 ahead on the other rows, the one ahead on this row,
/// cap - 1) when its cube is uniform, else 1. Returns the voxels whose distance changed
/// (empty if none). `bound` is scratch of n voxels.
template <int kSx>
RunDistanceField::Span rowDistances(const RowInputs& in, std::uint8_t* distance, int lo, int hi, int n,
                                    std::uint8_t* bound) {
  const std::uint8_t* const cube = in.cube;
  const std::uint8_t *const d0 = in.ahead[0], *const d1 = in.ahead[1], *const d2 = in.ahead[2];
  const int first = kSx > 0 ? std::max(0, lo - kCap) : lo, last = kSx > 0 ? hi : std::min(n - 1, hi + kCap);
  // First what does not depend on this row's own distances, without a branch so that it
  // vectorises: 1 + bound[x] is the distance unless the one ahead on the row is smaller, and a
  // voxel whose cube is not uniform gets bound 0 (distance 1).
  for (int x = first; x <= last; ++x) {
    const std::uint8_t least = std::min(std::min(std::min(d0[x], d0[x + kSx]), std::min(d1[x], d1[x + kSx])),
                                        std::min(std::min(d2[x], d2[x + kSx]), static_cast<std::uint8_t>(kCap - 1)));
    bound[x] = cube[x] != 0 ? least : 0;
  }
  // Then the recurrence along the row, from the end ahead: d[x] = 1 + min(bound[x], d[x + kSx]).
  const int start = kSx > 0 ? hi : lo, end = kSx > 0 ? lo : hi, stop = kSx > 0 ? first - 1 : last + 1;
  std::uint8_t ahead = distance[start + kSx];
  int changed_lo = INT_MAX, changed_hi = INT_MIN;
  bool last_changed = false;
  int x = start;
#ifdef __SSE2__
  // Sixteen voxels at a time as a min-plus scan: unrolled, d[x] = 1 + the least of
  // bound[x + k kSx] + k over the block's voxels from x on, and of the distance of the voxel
  // ahead of the block + the voxels between.
  // Past the span a voxel's inputs are as they were, so once a block's last voxel is as it
  // was so are all behind it: the scan stops there, as the voxel-by-voxel loop below does.
  const __m128i ones = _mm_set1_epi8(-1);
  // What the voxel ahead of the block adds to voxel i's least: its distance + the voxels
  // between them, 15 - i along +x and i along -x.
  const __m128i steps = kSx > 0 ? _mm_setr_epi8(15, 14, 13, 12, 11, 10, 9, 8, 7, 6, 5, 4, 3, 2, 1, 0)
                                : _mm_setr_epi8(0, 1, 2, 3, 4, 5, 6, 7, 8, 9, 10, 11, 12, 13, 14, 15);
  // t[i] = min(t[i], t[i + s kSx] + s), reading the saturated 0xff past the block's end ahead.
  const auto fold = [&](__m128i t, auto shift) {
    constexpr int s = decltype(shift)::value;
    const __m128i ahead_of = kSx > 0 ? _mm_or_si128(_mm_srli_si128(t, s), _mm_slli_si128(ones, 16 - s))
                                     : _mm_or_si128(_mm_slli_si128(t, s), _mm_srli_si128(ones, 16 - s));
    return _mm_min_epu8(t, _mm_adds_epu8(ahead_of, _mm_set1_epi8(static_cast<char>(s))));
  };
  while (kSx > 0 ? x - 15 > stop : x + 15 < stop) {
    const int block = kSx > 0 ? x - 15 : x;  // the block's least x
    __m128i t = _mm_loadu_si128(reinterpret_cast<const __m128i*>(bound + block));
    t = fold(t, std::integral_constant<int, 1>{});
    t = fold(t, std::integral_constant<int, 2>{});
    t = fold(t, std::integral_constant<int, 4>{});
    t = fold(t, std::integral_constant<int, 8>{});
    t = _mm_min_epu8(t, _mm_adds_epu8(_mm_set1_epi8(static_cast<char>(ahead)), steps));
    const __m128i d = _mm_add_epi8(t, _mm_set1_epi8(1));
    const __m128i before = _mm_loadu_si128(reinterpret_cast<const __m128i*>(distance + block));
    const auto changed = static_cast<unsigned>(_mm_movemask_epi8(_mm_cmpeq_epi8(d, before))) ^ 0xffffu;
    _mm_storeu_si128(reinterpret_cast<__m128i*>(distance + block), d);
    if (changed != 0) {
      changed_lo = std::min(changed_lo, block + std::countr_zero(changed));
      changed_hi = std::max(changed_hi, block + 31 - std::countl_zero(changed));
    }
    const int behind = kSx > 0 ? 0 : 15;  // the block's voxel last in the recurrence
    ahead = distance[block + behind];
    last_changed = (changed >> behind & 1u) != 0;
    x = kSx > 0 ? block - 1 : block + 16;
    if ((kSx > 0 ? x < end : x > end) && !last_changed) return {changed_lo, changed_hi};
  }
#endif
  // Voxel by voxel (the rest of the row); the changed voxels' least and greatest x kept by
  // selection, for the values change at random.
  for (; x != stop; x -= kSx) {
    const bool past_end = kSx > 0 ? x < end : x > end;
    if (past_end && !last_changed) break;
    const auto d = static_cast<std::uint8_t>(std::min(bound[x], ahead) + 1);
    last_changed = d != distance[x];
    distance[x] = d;
    changed_lo = last_changed ? std::min(changed_lo, x) : changed_lo;
    changed_hi = last_changed ? std::max(changed_hi, x) : changed_hi;
    ahead = d;
  }
  return {changed_lo, changed_hi};
}

/// Unites the x span of `region` into the span of each of its rows (y + ny * z) in `rows`.
template <class Region>
void uniteRows(std::vector<RunDistanceField::Span>& rows, std::size_t ny, const Region& region) {
  for (int z = region.lo.z(); z <= region.hi.z(); ++z) {
    for (int y = region.lo.y(); y <= region.hi.y(); ++y) {
      rows[static_cast<std::size_t>(z) * ny + static_cast<std::size_t>(y)].unite(region.lo.x(), region.hi.x());
    }
  }
}

/// Capacity along an axis for a box of `size` voxels: the voxel outside on each side, and with
/// `room`, room to grow by an eighth and 8 voxels more on each side. Every voxel of the arrays
/// is written when they are allocated, so room costs its pages at once: a box built from
/// scratch gets none (on a flat building floor the room tripled the arrays: 9 voxels more
/// on each side of a box 40 voxels high), a box that grew once gets it for the next growth.
std::size_t capacityFor(std::uint32_t size, bool room) {
  return std::size_t{size} + 2 * (1 + (room ? 8 + size / 8 : 0));
}

}  // namespace

template <class Then>
void RunDistanceField::allocate(const std::size_t capacity[3], const Then& then) {
  const std::size_t voxels = capacity[0] * capacity[1] * capacity[2];
  if (index_.size() != voxels || cube_.size() != voxels || distance_.size() != voxels * kernels::kOctants) {
    index_ = LargeArray<std::uint32_t>(voxels);
    cube_ = LargeArray<std::uint8_t>(voxels);
    distance_ = LargeArray<std::uint8_t>(voxels * kernels::kOctants);
  }
  std::copy(capacity, capacity + 3, capacity_);
  const std::size_t layer = capacity[0] * capacity[1];
  ForkJoin::parallelFor(capacity[2], [&](std::size_t z) {
    const std::size_t first = z * layer;
    std::fill_n(index_.data() + first, layer, 0u);
    std::fill_n(cube_.data() + first, layer, std::uint8_t{1});
    for (unsigned o = 0; o < kernels::kOctants; ++o) std::fill_n(distances(o, first), layer, kCap);
    then(z);
  });
}

void RunDistanceField::reset(const std::uint32_t size[3]) {
  std::copy(size, size + 3, size_);
  // The arrays' layout is kept where it holds the box with the room a new one would have and
  // at most kKeptLayout times its voxels: a field reset for one map after another of about the
  // same extent reuses its memory, and a box that grows as it did last time fits in place.
  std::size_t capacity[3] = {capacityFor(size[0], false), capacityFor(size[1], false), capacityFor(size[2], false)};
  constexpr std::size_t kKeptLayout = 8;
  if (capacity_[0] >= capacity[0] && capacity_[1] >= capacity[1] && capacity_[2] >= capacity[2] &&
      capacityVoxels() <= kKeptLayout * capacity[0] * capacity[1] * capacity[2]) {
    std::copy(capacity_, capacity_ + 3, capacity);
  }
  for (int a = 0; a < 3; ++a) window_[a] = static_cast<int>((capacity[a] - size[a]) / 2);
  allocate(capacity, [](std::size_t) {});
  for (auto& spans : computed_) spans.assign(std::size_t{size[1]} * size[2], Span{});
  pending_.clear();
  unsettled_.clear();
  // Fresh arrays read as outside everywhere (index 0, every cube uniform, the cap), which the
  // distances' rule holds for: the indices set next change flags, and those seed the passes.
  if (size[0] > 0 && size[1] > 0 && size[2] > 0) {
    changed(Index3::Zero(), Index3(static_cast<int>(size[0]) - 1, static_cast<int>(size[1]) - 1, static_cast<int>(size[2]) - 1));
  }
}

void RunDistanceField::grow(const std::uint32_t size[3], const Index3& offset) {
  const std::uint32_t old_size[3] = {size_[0], size_[1], size_[2]};
  int window[3];
  bool fits = true;
  for (int a = 0; a < 3; ++a) {
    window[a] = window_[a] - offset[a];
    fits = fits && window[a] >= 1 && static_cast<std::size_t>(window[a]) + size[a] + 1 <= capacity_[a];
  }
  if (fits) {  // the arrays hold the new box already, outside the old one as outside reads
    std::copy(window, window + 3, window_);
  } else {
    // New arrays with room to grow; the old box's indices and distances, and the flags of the
    // cubes from one voxel before it (those that hold outside voxels too), at their new places,
    // copied by the task that writes their layer.
    LargeArray<std::uint32_t> old_index = std::move(index_);
    LargeArray<std::uint8_t> old_cube = std::move(cube_);
    LargeArray<std::uint8_t> old_distance = std::move(distance_);
    const std::size_t old_voxels = capacityVoxels();
    const auto old_at = [this](int y, int z) { return at(y, z); };  // before the new layout
    const auto old_rows = static_cast<std::size_t>(old_size[1]) + 1;  // box rows y >= -1 of a layer
    std::vector<std::size_t> from;  // old offsets of box rows y, z >= -1
    for (int z = -1; z < static_cast<int>(old_size[2]); ++z) {
      for (int y = -1; y < static_cast<int>(old_size[1]); ++y) from.push_back(old_at(y, z));
    }
    const std::size_t capacity[3] = {capacityFor(size[0], true), capacityFor(size[1], true), capacityFor(size[2], true)};
    for (int a = 0; a < 3; ++a) window_[a] = static_cast<int>((capacity[a] - size[a]) / 2);
    const auto copy_layer = [&](std::size_t layer) {
      const int z = static_cast<int>(layer) - window_[2] - offset.z();  // in the old box
      if (z < -1 || z >= static_cast<int>(old_size[2])) return;
      for (int y = -1; y < static_cast<int>(old_size[1]); ++y) {
        const std::size_t row = static_cast<std::size_t>(z + 1) * old_rows + static_cast<std::size_t>(y + 1);
        const std::size_t to = at(y + offset.y(), z + offset.z()) + static_cast<std::size_t>(offset.x());
        std::copy_n(old_cube.data() + from[row] - 1, old_size[0] + 1, cube_.data() + to - 1);
        if (y < 0 || z < 0) continue;
        std::copy_n(old_index.data() + from[row], old_size[0], index_.data() + to);
        for (unsigned o = 0; o < kernels::kOctants; ++o) {
          std::copy_n(old_distance.data() + o * old_voxels + from[row], old_size[0], distances(o, to));
        }
      }
    };
    allocate(capacity, copy_layer);
    // Arrays a box outgrew: a box that grows asks for larger ones, so they are not kept.
    old_index.giveBack();
    old_cube.giveBack();
    old_distance.giveBack();
  }
  std::copy(size, size + 3, size_);
  for (auto& spans : computed_) spans.assign(std::size_t{size[1]} * size[2], Span{});
  // Changes not yet applied, now relative to the new box; and the new voxels, per axis the
  // slabs below and above the old box: index 0 and the cap as outside was, their entries to
  // be written. Their flags were computed with outside voxels as index 0, so they hold; but
  // those computed next to the old box may be 0, and a new voxel's distance reads the old
  // box's distances ahead: the shell one voxel around the old box is recomputed whatever its
  // flags, and the rest follows from changes.
  for (auto* regions : {&pending_, &unsettled_}) {
    for (Region& r : *regions) {
      r.lo += offset;
      r.hi += offset;
    }
  }
  const Index3 last(static_cast<int>(size[0]) - 1, static_cast<int>(size[1]) - 1, static_cast<int>(size[2]) - 1);
  Index3 shell_lo, shell_hi;  // the old box grown by one voxel, within the new one
  for (int a = 0; a < 3; ++a) {
    shell_lo[a] = std::max(0, offset[a] - 1);
    shell_hi[a] = std::min(last[a], offset[a] + static_cast<int>(old_size[a]));
  }
  const auto shell_face = [&](int a, int at) {  // the shell's voxels at coordinate `at` along axis a
    Index3 lo = shell_lo, hi = shell_hi;
    lo[a] = hi[a] = at;
    unsettled(lo, hi);
  };
  for (int a = 0; a < 3; ++a) {
    const int old_end = offset[a] + static_cast<int>(old_size[a]);
    if (offset[a] > 0) {
      Index3 hi = last;
      hi[a] = offset[a] - 1;
      changed(Index3::Zero(), hi);
      shell_face(a, shell_lo[a]);
    }
    if (old_end <= last[a]) {
      Index3 lo = Index3::Zero();
      lo[a] = old_end;
      changed(lo, last);
      shell_face(a, shell_hi[a]);
    }
  }
}

void RunDistanceField::joinPending() {
  const auto rows = [](const Region& r) { return std::make_tuple(r.lo.z(), r.lo.y(), r.hi.z(), r.hi.y()); };
  std::sort(pending_.begin(), pending_.end(), [&](const Region& a, const Region& b) {
    return std::make_tuple(rows(a), a.lo.x()) < std::make_tuple(rows(b), b.lo.x());
  });
  std::size_t kept = 0;
  for (std::size_t i = 0; i < pending_.size(); ++i) {
    const Region& r = pending_[i];
    if (kept > 0 && rows(pending_[kept - 1]) == rows(r) && pending_[kept - 1].hi.x() + 1 >= r.lo.x()) {
      pending_[kept - 1].hi.x() = std::max(pending_[kept - 1].hi.x(), r.hi.x());
    } else {
      pending_[kept++] = r;
    }
  }
  pending_.resize(kept);
}

void RunDistanceField::updateCubes() {
  const int n[3] = {static_cast<int>(size_[0]), static_cast<int>(size_[1]), static_cast<int>(size_[2])};
  // The cubes holding a voxel of region r: those from one voxel before it (outside voxels
  // included), so cube layers z = -1 .. n[2] - 1. One task per layer, over the regions that
  // reach it; each task writes its layer's flags and its own list of changed spans.
  const auto layers = static_cast<std::size_t>(n[2]) + 1;
  std::vector<std::vector<std::uint32_t>> regions_of(layers);
  for (std::size_t i = 0; i < pending_.size(); ++i) {
    const Region& r = pending_[i];
    for (int z = std::max(-1, r.lo.z() - 1); z <= std::min(n[2] - 1, r.hi.z()); ++z) {
      regions_of[static_cast<std::size_t>(z + 1)].push_back(static_cast<std::uint32_t>(i));
    }
  }
  std::vector<std::vector<FlagChange>> changes(layers);
  const auto layer = [&](std::size_t task) {
    const int z = static_cast<int>(task) - 1;
    std::vector<std::uint8_t> fresh_flags(capacity_[0]);  // one row of flags
    std::uint8_t* const fresh = fresh_flags.data() + window_[0];
    for (const std::uint32_t i : regions_of[task]) {
      const Region& r = pending_[i];
      const int x0 = std::max(-1, r.lo.x() - 1), x1 = std::min(n[0] - 1, r.hi.x());
      for (int y = std::max(-1, r.lo.y() - 1); y <= std::min(n[1] - 1, r.hi.y()); ++y) {
        const std::uint32_t *const r0 = index_.data() + at(y, z), *const r1 = index_.data() + at(y + 1, z);
        const std::uint32_t *const r2 = index_.data() + at(y, z + 1), *const r3 = index_.data() + at(y + 1, z + 1);
        std::uint8_t* const flags = cube_.data() + at(y, z);
        std::uint8_t differ_any = 0;
        for (int x = x0; x <= x1; ++x) {  // without a branch, so that it vectorises
          const std::uint32_t c = r0[x];
          const std::uint32_t differ = (c ^ r0[x + 1]) | (c ^ r1[x]) | (c ^ r1[x + 1]) | (c ^ r2[x]) | (c ^ r2[x + 1]) |
                                       (c ^ r3[x]) | (c ^ r3[x + 1]);
          fresh[x] = differ == 0 ? 1 : 0;
          differ_any |= fresh[x] ^ flags[x];
        }
        if (differ_any == 0) continue;  // the row's flags as they were
        Span span;
        for (int x = x0; x <= x1; ++x) {
          if (fresh[x] != flags[x]) span.unite(x, x);
        }
        std::copy(fresh + span.lo, fresh + span.hi + 1, flags + span.lo);
        changes[task].push_back({y, z, span});
      }
    }
  };
  ForkJoin::parallelFor(layers, layer);
  flag_changes_.clear();
  for (const std::vector<FlagChange>& list : changes) flag_changes_.insert(flag_changes_.end(), list.begin(), list.end());
}

void RunDistanceField::updateOctant(unsigned octant) {
  const int sx = (octant & 1) != 0 ? -1 : 1, sy = (octant & 2) != 0 ? -1 : 1, sz = (octant & 4) != 0 ? -1 : 1;
  const int nx = static_cast<int>(size_[0]), ny = static_cast<int>(size_[1]), nz = static_cast<int>(size_[2]);
  std::vector<Span> spans(static_cast<std::size_t>(ny) * static_cast<std::size_t>(nz));
  const auto row = [ny](int y, int z) { return static_cast<std::size_t>(z) * static_cast<std::size_t>(ny) + static_cast<std::size_t>(y); };
  // A voxel's cube has its least corner one voxel back along each negative axis: a changed
  // flag at corner c is that of voxel c + back. Unsettled voxels are computed whatever their flags.
  const int back_x = sx < 0 ? 1 : 0, back_y = sy < 0 ? 1 : 0, back_z = sz < 0 ? 1 : 0;
  for (const FlagChange& f : flag_changes_) {
    const int y = f.y + back_y, z = f.z + back_z;
    const int x0 = std::max(0, f.x.lo + back_x), x1 = std::min(nx - 1, f.x.hi + back_x);
    if (y >= 0 && z >= 0 && y < ny && z < nz && x0 <= x1) spans[row(y, z)].unite(x0, x1);
  }
  for (const Region& r : unsettled_) uniteRows(spans, static_cast<std::size_t>(ny), r);
  std::vector<std::uint8_t> bound(static_cast<std::size_t>(nx));
  std::vector<Span>& computed = computed_[octant];
  std::fill(computed.begin(), computed.end(), Span{});
  for (int n = 0; n < nz; ++n) {
    const int z = sz > 0 ? nz - 1 - n : n;
    for (int m = 0; m < ny; ++m) {
      const int y = sy > 0 ? ny - 1 - m : m;
      const Span span = spans[row(y, z)];
      if (span.empty()) continue;
      const RowInputs in{cube_.data() + at(y - back_y, z - back_z) - back_x,
                         {distances(octant, at(y + sy, z)), distances(octant, at(y, z + sz)),
                          distances(octant, at(y + sy, z + sz))}};
      std::uint8_t* const distance = distances(octant, at(y, z));
      const Span changed = sx > 0 ? rowDistances<1>(in, distance, span.lo, span.hi, nx, bound.data())
                                  : rowDistances<-1>(in, distance, span.lo, span.hi, nx, bound.data());
      if (changed.empty()) continue;
      computed[row(y, z)] = changed;
      // What changed reaches the rows behind: their voxels at the same x and one step behind.
      const int changed_lo = changed.lo - (sx > 0 ? 1 : 0), changed_hi = changed.hi + (sx < 0 ? 1 : 0);
      const int behind_y = y - sy, behind_z = z - sz;
      const bool y_in = behind_y >= 0 && behind_y < ny, z_in = behind_z >= 0 && behind_z < nz;
      const int x0 = std::max(0, changed_lo), x1 = std::min(nx - 1, changed_hi);
      if (y_in) spans[row(behind_y, z)].unite(x0, x1);
      if (z_in) spans[row(y, behind_z)].unite(x0, x1);
      if (y_in && z_in) spans[row(behind_y, behind_z)].unite(x0, x1);
    }
  }
}

std::size_t RunDistanceField::update(kernels::SnapshotEntry* entries) {
  if (pending_.empty()) return 0;
  joinPending();
  updateCubes();
  ForkJoin::parallelFor(kernels::kOctants, [this](unsigned octant) { updateOctant(octant); });
  // The entries of every voxel whose index or some distance changed, a layer of rows per task.
  const int ny = static_cast<int>(size_[1]);
  written_.assign(std::size_t{size_[1]} * size_[2], Span{});
  for (const Region& r : pending_) uniteRows(written_, size_[1], r);
  pending_.clear();
  unsettled_.clear();
  std::vector<std::size_t> written(size_[2], 0);
  ForkJoin::parallelFor(static_cast<int>(size_[2]), [&](int z) {
    for (int y = 0; y < ny; ++y) {
      const std::size_t r = static_cast<std::size_t>(z) * static_cast<std::size_t>(ny) + static_cast<std::size_t>(y);
      Span span = written_[r];
      for (const auto& spans : computed_) {
        if (!spans[r].empty()) span.unite(spans[r].lo, spans[r].hi);
      }
      if (span.empty()) continue;
      // Each entry written once, from the row's index and its distances in every octant.
      const std::size_t from = at(y, z) + static_cast<std::size_t>(span.lo);
      const auto count = static_cast<std::size_t>(span.hi - span.lo + 1);
      const std::uint32_t* const index = index_.data() + from;
      std::array<const std::uint8_t*, kernels::kOctants> distance;
      for (unsigned o = 0; o < kernels::kOctants; ++o) distance[o] = distances(o, from);
      kernels::SnapshotEntry* const out = entries + r * size_[0] + static_cast<std::size_t>(span.lo);
      for (std::size_t i = 0; i < count; ++i) {
        kernels::SnapshotEntry e = index[i];
        for (unsigned o = 0; o < kernels::kOctants; ++o) e = kernels::withRunDistance(e, o, distance[o][i]);
        out[i] = e;
      }
      written[static_cast<std::size_t>(z)] += static_cast<std::size_t>(span.hi - span.lo + 1);
    }
  });
  std::size_t total = 0;
  for (const std::size_t w : written) total += w;
  return total;
}

}  // namespace nbv::ig
