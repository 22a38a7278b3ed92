#pragma once
// Private: the packet walk of markRays(), written once over the register types of a lane
// width S (simd_avx2.hpp: 4 rays, simd_avx512.hpp: 8 rays). Each lane runs OctoMap's DDA
// (LaneDda, dda_lanes.hpp) with the operations of traverseRayKeys(), which stays the oracle,
// so every lane visits the scalar walk's voxels.
//
// RayBatcher sets the rays up a packet at a time, in the order given, and checks them ahead
// of the walk. A packet walks a ray only if both its end voxels lie at least one voxel inside
// the box: along each axis the walk moves monotonically from the origin's voxel and overshoots
// the end voxel by at most one (rounding only, far below a voxel), so such a ray stays in the
// box. Its voxel is then a byte offset into the box, set up in a double (exact below 2^31),
// walked in S's offset lanes (S::O: doubles for AVX2, 32-bit integers for AVX-512) and moved
// by the stride of the axis it steps along, so "reached the end voxel" is one comparison. The
// other rays take the scalar walk as they are set up.
//
// A packet's rays start together and the packet steps until all have ended; an ended lane stays
// on its last voxel. Neighbouring rays of a scan cross nearly the same number of voxels, so
// the lanes waste few steps, and the packet leaves its loop once per kLanes rays (refilling
// lanes one by one as their rays end costs more).
//
// Included by one source per lane width, inside that source's target options. The walk has
// internal linkage: each source has its own copy.

#include "dda_lanes.hpp"
#include "mark_rays_impl.hpp"

#include <algorithm>
#include <cstdint>
#include <span>

namespace nbv::kernels::detail {
namespace {

/// Rays set up and checked ahead of the walk, a packet's worth of columns at a time (offsets:
/// byte offsets into the box, as doubles). A lane of a packet without a ray is parked: it sits
/// on the first voxel of another ray of its packet (written before the packet walks), with no
/// offset step and that voxel as its end, so it ends at its first step.
struct Batch {
  static constexpr int kCapacity = 64;  ///< rays, a multiple of every packet width
  alignas(64) double offset[kCapacity];
  alignas(64) double end_offset[kCapacity];
  alignas(64) double t_max[3][kCapacity];
  alignas(64) double t_delta[3][kCapacity];
  alignas(64) double offset_step[3][kCapacity];  ///< step[a] * stride[a]
  alignas(64) double length[kCapacity];
  int count = 0, next = 0;  ///< multiples of the packet width
};

/// Fills batches with the rays of one markRays() call, in the order given, a packet of kLanes
/// rays at a time.
template <class S, MarkSpec::Mode kMode>
class RayBatcher {
  static constexpr int kLanes = S::kLanes;
  static constexpr unsigned kAllLanes = (1u << kLanes) - 1u;
  static_assert(Batch::kCapacity % kLanes == 0);
  using D = LaneDoubles<S>;
  using M = LaneMask<S>;
  using Dda = LaneDda<S>;

 public:
  RayBatcher(std::span<const Eigen::Vector3f> origins, std::span<const Eigen::Vector3f> ends,
             const VoxelLattice& lattice, const DenseBox& box, const MarkSpec& spec, const OutsideSink& outside)
      : origins_(origins), ends_(ends), lattice_(lattice), box_(box), spec_(spec), outside_(outside),
        stride_{1.0, static_cast<double>(box.size[0]), static_cast<double>(box.size[0]) * box.size[1]} {}

  /// The packet to walk next, as a column of batch(); false when no ray is left. Refills the
  /// batch when it is used up.
  bool next(int& j) {
    if (batch_.next == batch_.count) fill();
    if (batch_.next == batch_.count) return false;
    j = batch_.next;
    batch_.next += kLanes;
    return true;
  }
  const Batch& batch() const { return batch_; }

 private:
  /// Refills the batch with the next rays that visit anything in the packet. Each ray's first
  /// voxel (the origin's) and end flag are written here, and rays that may leave the box are
  /// walked here by the scalar oracle. Leaves the batch empty when no ray is left. Not
  /// inlined: it is called once per batch, and its calls must not push the packet loop's
  /// registers to memory.
  [[gnu::noinline]] void fill();
  /// Writes the first voxel and end flag of the `count` rays of a packet, walks those the
  /// packet cannot (`rays` & ~`packet`) with the scalar oracle, and checks byte distances.
  void writeAlone(const Eigen::Vector3f* const from[], const Eigen::Vector3f* const to[], int count,
                  const typename Dda::Setup& s, unsigned rays, unsigned packet, D at_origin, D at_end, unsigned in_box);
  /// Appends a packet of the rays in `take` (not none); the other lanes are parked.
  void append(const typename Dda::Setup& s, D at_origin, D at_end, unsigned take);

  std::span<const Eigen::Vector3f> origins_, ends_;
  const VoxelLattice& lattice_;
  const DenseBox& box_;
  const MarkSpec& spec_;
  const OutsideSink& outside_;
  const double stride_[3];
  std::size_t next_ = 0;  ///< the next ray of ends_ to set up
  Batch batch_;
};

template <class S, MarkSpec::Mode kMode>
void RayBatcher<S, kMode>::fill() {
  batch_.count = batch_.next = 0;
  while (batch_.count < Batch::kCapacity && next_ < ends_.size()) {
    const int count = static_cast<int>(std::min<std::size_t>(kLanes, ends_.size() - next_));
    const Eigen::Vector3f* from[kLanes];
    const Eigen::Vector3f* to[kLanes];
    alignas(64) float points[2][3][kLanes];  // origins, ends
    for (int j = 0; j < kLanes; ++j) {
      const std::size_t i = next_ + static_cast<std::size_t>(std::min(j, count - 1));  // short: the last ray again
      from[j] = &origins_[origins_.size() == 1 ? 0 : i];
      to[j] = &ends_[i];
      for (int a = 0; a < 3; ++a) {
        points[0][a][j] = (*from[j])[a];
        points[1][a][j] = (*to[j])[a];
      }
    }
    next_ += static_cast<std::size_t>(count);
    const typename S::F origin[3] = {S::loadF(points[0][0]), S::loadF(points[0][1]), S::loadF(points[0][2])};
    const typename S::F end[3] = {S::loadF(points[1][0]), S::loadF(points[1][1]), S::loadF(points[1][2])};
    typename Dda::Setup s;
    const unsigned same_voxel = Dda::setup(origin, end, lattice_, s).bits();

    // Both end voxels at least one voxel inside the box (DenseBox::holdsWithMargin), the end
    // voxel in the box (for its flag), and both voxels as byte offsets,
    // (z * size_y + y) * size_x + x relative to the box's corner.
    const D zero = S::zero();
    M inside = zero == zero, end_in_box = inside;
    D at_origin = zero, at_end = zero;
    for (int a = 2; a >= 0; --a) {
      const D min(box_.min[a]), size(box_.size[a]);
      const D last(box_.size[a] - 1.0), last_inner(box_.size[a] - 2.0);
      const D o = s.key_origin[a] - min, e = s.key_end[a] - min;
      inside = inside & (((o > zero) & (o <= last_inner)) & ((e > zero) & (e <= last_inner)));
      end_in_box = end_in_box & ((zero <= e) & (e <= last));
      at_origin = at_origin * size + o;
      at_end = at_end * size + e;
    }
    const unsigned rays = ((1u << count) - 1u) & ~same_voxel;
    const unsigned packet = rays & inside.bits();
    const unsigned in_box = end_in_box.bits();
    if (kMode == MarkSpec::Mode::Store && packet == kAllLanes) {
      // The common case: kLanes rays, all in the packet (so their end voxels lie in the box).
      const std::uint8_t value = spec_.value;
      S::forEachAt(box_.data, S::toOffsets(at_origin), kAllLanes, [value](std::uint8_t* b) { storeByte(b, value); });
      if (spec_.end_flags != nullptr) {
        S::forEachAt(spec_.end_flags, S::toOffsets(at_end), kAllLanes, [](std::uint8_t* b) { storeByte(b, 1); });
      }
    } else {
      writeAlone(from, to, count, s, rays, packet, at_origin, at_end, in_box);
    }
    if (packet != 0) append(s, at_origin, at_end, packet);
  }
}

template <class S, MarkSpec::Mode kMode>
void RayBatcher<S, kMode>::writeAlone(const Eigen::Vector3f* const from[], const Eigen::Vector3f* const to[],
                                      int count, const typename Dda::Setup& s, unsigned rays, unsigned packet,
                                      D at_origin, D at_end, unsigned in_box) {
  alignas(64) std::int32_t origin[kLanes], end[kLanes];
  S::offsets(at_origin, origin);
  S::offsets(at_end, end);
  alignas(64) double keys[2][3][kLanes];
  for (int a = 0; a < 3; ++a) {
    S::store(keys[0][a], s.key_origin[a]);
    S::store(keys[1][a], s.key_end[a]);
  }
  if (spec_.end_flags != nullptr) {
    for (int lane = 0; lane < count; ++lane) {
      flagEnd(spec_, ((in_box >> lane) & 1u) != 0, static_cast<std::uint32_t>(end[lane]));
    }
  }
  for (int lane = 0; lane < count; ++lane) {
    if (((rays >> lane) & 1u) == 0) continue;
    const auto key = [&keys, lane](int e) {
      return Index3(static_cast<int>(keys[e][0][lane]), static_cast<int>(keys[e][1][lane]),
                    static_cast<int>(keys[e][2][lane]));
    };
    checkStepRange(spec_, key(0), key(1));
    if (((packet >> lane) & 1u) == 0) {
      markRayScalar(*from[lane], *to[lane], lattice_, box_, spec_, outside_);
    } else if constexpr (kMode == MarkSpec::Mode::Store) {
      writeByte(box_.data + static_cast<std::uint32_t>(origin[lane]), spec_, 0);
    }  // (MinStepIndex writes nothing for a ray's first voxel, k = 0)
  }
}

template <class S, MarkSpec::Mode kMode>
void RayBatcher<S, kMode>::append(const typename Dda::Setup& s, D at_origin, D at_end, unsigned take) {
  const int j = batch_.count;
  batch_.count += kLanes;
  const M in = M::of(take);
  if (take != kAllLanes) {
    alignas(64) double at[kLanes];
    S::store(at, at_origin);
    const D parking(at[__builtin_ctz(take)]);
    at_origin = select(in, at_origin, parking);
    at_end = select(in, at_end, parking);
  }
  S::store(batch_.offset + j, at_origin);
  S::store(batch_.end_offset + j, at_end);
  for (int a = 0; a < 3; ++a) {
    S::store(batch_.t_max[a] + j, s.t_max[a]);
    S::store(batch_.t_delta[a] + j, s.t_delta[a]);
    S::store(batch_.offset_step[a] + j, zeroUnless(in, s.step[a] * D(stride_[a])));
  }
  S::store(batch_.length + j, s.length);
}

template <class S, MarkSpec::Mode kMode>
class MarkPacketWalk {
  static constexpr unsigned kAllLanes = (1u << S::kLanes) - 1u;
  using D = LaneDoubles<S>;
  using M = LaneMask<S>;
  /// Byte offsets into the box in S's offset lanes (S::O: doubles for AVX2, 32-bit integers
  /// for AVX-512), moved and compared by S's overloads for them, as LaneDda::step() moves them.
  using O = typename S::O;
  using Dda = LaneDda<S>;

 public:
  MarkPacketWalk(std::span<const Eigen::Vector3f> origins, std::span<const Eigen::Vector3f> ends,
                 const VoxelLattice& lattice, const DenseBox& box, const MarkSpec& spec, const OutsideSink& outside)
      : rays_(origins, ends, lattice, box, spec, outside), box_(box), spec_(spec) {}

  void run();

 private:
  /// A packet's rays in registers. `ended`: the lanes whose ray has ended; `last`: each lane's
  /// latest voxel, which an ended lane keeps.
  struct Packet {
    D dx, dy, dz, length;  ///< t_delta
    O ox, oy, oz, end_offset;  ///< offset_step
    D tx, ty, tz;
    O offset, last;
    M ended;
  };

  /// Loads the next packet of rays; false when no ray is left. Inlined, as step() is, so that
  /// the packet's registers never have their address taken (the byte stores of the walk could
  /// alias anything addressable, which would keep the packet in memory).
  [[gnu::always_inline]] bool load(Packet& p);
  /// One step of every lane: RayWalk::next() and, in Store mode, `value` at its voxel in `data`
  /// (an ended lane writes its last voxel's byte again, which changes nothing). Returns the
  /// lanes that have ended. (The caller holds `data` and `value` in registers: read from the
  /// members, they would be reloaded after every byte store, which may alias them.)
  [[gnu::always_inline]] unsigned step(Packet& p, std::uint8_t* data, std::uint8_t value);

  RayBatcher<S, kMode> rays_;
  const DenseBox& box_;
  const MarkSpec& spec_;
};

template <class S, MarkSpec::Mode kMode>
inline bool MarkPacketWalk<S, kMode>::load(Packet& p) {
  int j = 0;
  if (!rays_.next(j)) return false;
  const Batch& b = rays_.batch();
  p.dx = S::load(b.t_delta[0] + j);
  p.dy = S::load(b.t_delta[1] + j);
  p.dz = S::load(b.t_delta[2] + j);
  p.ox = S::toOffsets(S::load(b.offset_step[0] + j));
  p.oy = S::toOffsets(S::load(b.offset_step[1] + j));
  p.oz = S::toOffsets(S::load(b.offset_step[2] + j));
  p.end_offset = S::toOffsets(S::load(b.end_offset + j));
  p.length = S::load(b.length + j);
  p.tx = S::load(b.t_max[0] + j);
  p.ty = S::load(b.t_max[1] + j);
  p.tz = S::load(b.t_max[2] + j);
  p.offset = S::toOffsets(S::load(b.offset + j));
  p.last = p.offset;
  p.ended = M::of(0u);
  return true;
}

template <class S, MarkSpec::Mode kMode>
inline unsigned MarkPacketWalk<S, kMode>::step(Packet& p, std::uint8_t* data, std::uint8_t value) {
  Dda::step(p.tx, p.ty, p.tz, p.dx, p.dy, p.dz, p.offset, p.ox, p.oy, p.oz);
  // RayWalk::next() returning false: the end voxel reached, or the next border beyond the length.
  p.ended = p.ended | (M(S::eq(p.offset, p.end_offset)) | Dda::pastLength(p.tx, p.ty, p.tz, p.length));
  if constexpr (kMode == MarkSpec::Mode::Store) {
    p.last = S::select(p.ended, p.last, p.offset);
    S::forEachAt(data, p.last, kAllLanes, [value](std::uint8_t* b) { storeByte(b, value); });
  }
  return p.ended.bits();
}

template <class S, MarkSpec::Mode kMode>
void MarkPacketWalk<S, kMode>::run() {
  // No function call in the step loops: a call would force every vector register (all are
  // caller-saved) to be spilled and reloaded at each step.
  std::uint8_t* const data = box_.data;
  const std::uint8_t value = spec_.value;
  Packet p;
  if constexpr (kMode == MarkSpec::Mode::Store) {
    while (load(p)) {
      while (step(p, data, value) != kAllLanes) {
      }
    }
  } else {
    // MinStepIndex: a packet's lanes start together, so a voxel's k is the step count.
    while (load(p)) {
      for (int k = 1;; ++k) {
        const unsigned visit = ~step(p, data, value) & kAllLanes;
        if (visit == 0) break;
        const auto d = static_cast<std::uint8_t>(k);
        S::forEachAt(data, p.offset, visit, [d](std::uint8_t* b) { lowerByte(b, d); });
      }
    }
  }
}

/// markRays() in packets of S::kLanes rays; box.bytes() must be below 2^31.
template <class S>
void markRaysPackets(std::span<const Eigen::Vector3f> origins, std::span<const Eigen::Vector3f> ends,
                     const VoxelLattice& lattice, const DenseBox& box, const MarkSpec& spec,
                     const OutsideSink& outside) {
  if (spec.mode == MarkSpec::Mode::Store) {
    MarkPacketWalk<S, MarkSpec::Mode::Store>(origins, ends, lattice, box, spec, outside).run();
  } else {
    MarkPacketWalk<S, MarkSpec::Mode::MinStepIndex>(origins, ends, lattice, box, spec, outside).run();
  }
}

}  // namespace
}  // namespace nbv::kernels::detail
