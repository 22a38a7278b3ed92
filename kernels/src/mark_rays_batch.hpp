#pragma once
// Private, for the packet walks of markRays() only (AVX2 and AVX-512): rays set up four at a
// time and checked ahead of the walk, in groups that enter a packet together.
//
// A packet walks a ray only if both its end voxels lie at least one voxel inside the box:
// along each axis the walk moves monotonically from the origin's voxel and overshoots the end
// voxel by at most one (rounding only, far below a voxel), so such a ray stays in the box and
// its voxel is a byte offset into it. Other rays take the scalar walk here, as they are set up.

#include "dda_avx2.hpp"
#include "mark_rays_impl.hpp"

#include <immintrin.h>

#include <algorithm>
#include <atomic>
#include <cstdint>
#include <span>

namespace nbv::kernels::detail {
// Internal linkage: each packet walk's source has its own copy, called directly.
namespace {

/// Stores `byte` at plane[at[i]] for the four lanes of `at`. The offsets leave the register by
/// extraction, not through memory (a 16-byte store forwarded to 4-byte loads stalls on some
/// cores), and as unsigned 32-bit values, which address without a sign extension.
inline void storeAt4(std::uint8_t* plane, const __m128i& at, std::uint8_t byte) {
  const auto store = [plane, byte](int offset) {
    std::atomic_ref<std::uint8_t>(plane[static_cast<std::uint32_t>(offset)]).store(byte, std::memory_order_relaxed);
  };
  store(_mm_cvtsi128_si32(at));
  store(_mm_extract_epi32(at, 1));
  store(_mm_extract_epi32(at, 2));
  store(_mm_extract_epi32(at, 3));
}

/// Rays set up and checked ahead of the walk, in groups of four (offsets are byte offsets into
/// the box, as doubles). A lane of a group without a ray is parked: it sits on the first voxel
/// of a ray of its group (written before the group is walked), with no offset step and that
/// voxel as its end, so it ends at its first step.
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

/// Fills batches with the rays of one markRays() call, in the order given, for packets of
/// kWidth lanes (4 or 8): a batch holds whole packets, the last one padded with parked groups.
template <MarkSpec::Mode kMode, int kWidth>
class RayBatcher {
  static_assert(kWidth % 4 == 0 && Batch::kCapacity % kWidth == 0);

 public:
  RayBatcher(std::span<const Eigen::Vector3f> origins, std::span<const Eigen::Vector3f> ends,
             const VoxelLattice& lattice, const DenseBox& box, const MarkSpec& spec, const OutsideSink& outside)
      : origins_(origins), ends_(ends), lattice_(lattice), box_(box), spec_(spec), outside_(outside),
        stride_{1.0, static_cast<double>(box.size[0]), static_cast<double>(box.size[0]) * box.size[1]} {}

  /// The packet of kWidth rays to walk next, as an index into batch(); false when no ray is
  /// left. Refills the batch when it is used up.
  bool next(int& j) {
    if (batch_.next == batch_.count) fill();
    if (batch_.next == batch_.count) return false;
    j = batch_.next;
    batch_.next += kWidth;
    return true;
  }
  const Batch& batch() const { return batch_; }

 private:
  /// Refills the batch with the next rays that visit anything in the packet. Each ray's first
  /// voxel (the origin's) is written here, and rays that may leave the box are walked here by
  /// the scalar oracle. Leaves the batch empty when no ray is left. Not inlined: it is called
  /// once per batch, and its calls must not push the packet loop's registers to memory.
  [[gnu::noinline]] void fill();
  /// Appends the rays of one setupRays4() call as a group, lanes in `take` only (not none).
  void append(const RaySetups4& s, const __m256d offset[2], unsigned take);

  std::span<const Eigen::Vector3f> origins_, ends_;
  const VoxelLattice& lattice_;
  const DenseBox& box_;
  const MarkSpec& spec_;
  const OutsideSink& outside_;
  const double stride_[3];
  std::size_t next_ = 0;  ///< the next ray of ends_ to set up
  Batch batch_;
};

template <MarkSpec::Mode kMode, int kWidth>
void RayBatcher<kMode, kWidth>::fill() {
  batch_.count = batch_.next = 0;
  const __m128i zero = _mm_setzero_si128();
  while (batch_.count < Batch::kCapacity && next_ < ends_.size()) {
    const std::size_t count = std::min<std::size_t>(4, ends_.size() - next_);
    const Eigen::Vector3f* from[4];
    const Eigen::Vector3f* to[4];
    for (std::size_t j = 0; j < 4; ++j) {
      const std::size_t i = next_ + std::min(j, count - 1);  // short groups repeat their last ray
      from[j] = &origins_[origins_.size() == 1 ? 0 : i];
      to[j] = &ends_[i];
    }
    next_ += count;
    RaySetups4 s;
    setupRays4(from, to, lattice_, s);
    // Both end voxels at least one voxel inside the box (DenseBox::holdsWithMargin), and the
    // voxels as byte offsets: (z * size_y + y) * size_x + x relative to the box's corner.
    __m128i inside = _mm_set1_epi32(-1), end_in_box = inside;
    __m256d offset[2] = {_mm256_setzero_pd(), _mm256_setzero_pd()};  // origin's, end's
    for (int a = 2; a >= 0; --a) {
      const __m128i min = _mm_set1_epi32(box_.min[a]);
      const __m128i last_inner = _mm_set1_epi32(static_cast<int>(box_.size[a]) - 2);
      const std::int32_t* keys[2] = {s.key_origin[a], s.key_end[a]};
      for (int e = 0; e < 2; ++e) {
        const __m128i v = _mm_sub_epi32(_mm_load_si128(reinterpret_cast<const __m128i*>(keys[e])), min);
        inside = _mm_and_si128(inside, _mm_andnot_si128(_mm_cmpgt_epi32(v, last_inner), _mm_cmpgt_epi32(v, zero)));
        offset[e] = _mm256_add_pd(_mm256_mul_pd(offset[e], _mm256_set1_pd(box_.size[a])), _mm256_cvtepi32_pd(v));
        if (e == 1) {  // 0 <= v <= size - 1
          end_in_box = _mm_and_si128(end_in_box, _mm_andnot_si128(_mm_cmpgt_epi32(v, _mm_add_epi32(last_inner, _mm_set1_epi32(1))),
                                                                  _mm_cmpgt_epi32(v, _mm_set1_epi32(-1))));
        }
      }
    }
    // Byte offsets as int32 (one instruction; a double to size_t conversion takes a branch).
    const __m128i at_origin = _mm256_cvttpd_epi32(offset[0]);
    const __m128i at_end = _mm256_cvttpd_epi32(offset[1]);
    const auto in_box = static_cast<unsigned>(_mm_movemask_ps(_mm_castsi128_ps(end_in_box)));
    if (spec_.end_flags != nullptr) {
      if (count == 4 && in_box == 0xFu) {
        storeAt4(spec_.end_flags, at_end, 1);
      } else {
        alignas(16) std::int32_t end[4];
        _mm_store_si128(reinterpret_cast<__m128i*>(end), at_end);
        for (int lane = 0; lane < static_cast<int>(count); ++lane) {
          flagEnd(spec_, ((in_box >> lane) & 1u) != 0, static_cast<std::size_t>(end[lane]));
        }
      }
    }
    const unsigned rays = ((1u << count) - 1u) & ~s.same_voxel;
    const unsigned packet = rays & static_cast<unsigned>(_mm_movemask_ps(_mm_castsi128_ps(inside)));
    if (kMode == MarkSpec::Mode::Store && packet == 0xFu) {
      storeAt4(box_.data, at_origin, spec_.value);  // the common case: four rays in packets
    } else {
      alignas(16) std::int32_t origin[4];
      _mm_store_si128(reinterpret_cast<__m128i*>(origin), at_origin);
      for (int lane = 0; lane < static_cast<int>(count); ++lane) {
        if (((rays >> lane) & 1u) == 0) continue;
        checkStepRange(spec_, s.keyOrigin(lane), s.keyEnd(lane));
        if (((packet >> lane) & 1u) == 0) {
          markRayScalar(*from[lane], *to[lane], lattice_, box_, spec_, outside_);
        } else if constexpr (kMode == MarkSpec::Mode::Store) {
          writeByte(box_.data + static_cast<std::size_t>(origin[lane]), spec_, 0);
        }  // (MinStepIndex writes nothing for a ray's first voxel, k = 0)
      }
    }
    if (packet != 0) append(s, offset, packet);
  }
  if (batch_.count % kWidth != 0) {
    // Pad the last packet with a group parked on the first voxel of the group before it.
    const __m256d parked[2] = {_mm256_set1_pd(batch_.offset[batch_.count - 4]),
                               _mm256_set1_pd(batch_.offset[batch_.count - 4])};
    append(RaySetups4{}, parked, 0u);
  }
}

template <MarkSpec::Mode kMode, int kWidth>
void RayBatcher<kMode, kWidth>::append(const RaySetups4& s, const __m256d offset[2], unsigned take) {
  const int j = batch_.count;
  batch_.count += 4;
  const __m256d in = laneMask(take);
  __m256d origin = offset[0], end = offset[1];
  if (take != 0xFu && take != 0u) {
    alignas(32) double at[4];
    _mm256_store_pd(at, origin);
    const __m256d parking = _mm256_set1_pd(at[__builtin_ctz(take)]);
    origin = _mm256_blendv_pd(parking, origin, in);
    end = _mm256_blendv_pd(parking, end, in);
  }
  _mm256_store_pd(batch_.offset + j, origin);
  _mm256_store_pd(batch_.end_offset + j, end);
  for (int a = 0; a < 3; ++a) {
    const __m256d step = _mm256_mul_pd(_mm256_cvtepi32_pd(_mm_load_si128(reinterpret_cast<const __m128i*>(s.step[a]))),
                                       _mm256_set1_pd(stride_[a]));
    _mm256_store_pd(batch_.t_max[a] + j, _mm256_load_pd(s.t_max[a]));
    _mm256_store_pd(batch_.t_delta[a] + j, _mm256_load_pd(s.t_delta[a]));
    _mm256_store_pd(batch_.offset_step[a] + j, _mm256_and_pd(in, step));
  }
  _mm256_store_pd(batch_.length + j, _mm256_load_pd(s.length));
}

}  // namespace
}  // namespace nbv::kernels::detail
