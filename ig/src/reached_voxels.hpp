#pragma once
// Private: how IgEvaluator::visibleVoxels() gathers the voxels the rays of a view (or a path of
// views) reach, each voxel once with the greatest visibility P_v any ray reaches it with and the
// count of those rays.

#include "nbv/ig/evaluator.hpp"

#include <algorithm>
#include <cstddef>
#include <cstdint>
#include <vector>

namespace nbv::ig::detail {

/// The voxels rays reach, added visit by visit from one thread. Neighbouring rays cross nearly
/// the same voxels, so a direct-mapped table of recent voxels adds a voxel reached again to its
/// entry; what the table lets go is listed, and the list is folded (each voxel's entries into
/// one) once it holds `fold_at` entries, or twice as many as its last fold kept: the memory
/// follows the distinct voxels, not the visits. Neither the greatest visibility nor the sum of
/// rays depends on the order of the visits, so the voxels are the same however the rays were
/// shared among threads and whenever a list was folded.
class ReachedVoxels {
 public:
  static constexpr std::size_t kFoldAt = std::size_t{1} << 20;

  /// `room`: the entries the list starts with room for.
  explicit ReachedVoxels(std::size_t room, std::size_t fold_at = kFoldAt)
      : recent_(std::size_t{1} << kRecentBits), fold_at_(std::max<std::size_t>(fold_at, 1)) {
    list_.reserve(room);
  }

  /// One ray reaches voxel `ijk` with visibility `visibility`. `ijk` must lie within OctoMap's
  /// key range (+-2^15 per axis), as every voxel of a valid view's rays does.
  void add(const Index3& ijk, double visibility) {
    const std::uint64_t key = keyOf(ijk);
    Reach& slot = recent_[(key * 0x9E3779B97F4A7C15ull) >> (64 - kRecentBits)];  // Fibonacci hashing
    if (slot.key == key) {
      slot.visibility = std::max(slot.visibility, visibility);
      ++slot.rays;
      return;
    }
    if (slot.key != kNone) keep(slot);
    slot = {key, visibility, 1};
  }

  /// Moves the recent voxels to the list and folds it: each voxel once, in key order. The
  /// gatherers of several threads settle side by side, then merge() in linear time.
  void settle() {
    flush();
    if (!folded_) fold(list_);
    folded_ = true;
  }

  /// Adds what the settled `other` gathered to this settled one (and leaves `other` empty).
  void merge(ReachedVoxels& other) {
    std::vector<Reach> both(list_.size() + other.list_.size());
    std::merge(list_.begin(), list_.end(), other.list_.begin(), other.list_.end(), both.begin(), byKey);
    foldSorted(both);
    list_ = std::move(both);
    other.list_.clear();
  }

  /// Every voxel reached, each once, ordered by z, then y, then x (and leaves this empty).
  std::vector<VisibleVoxel> take() {
    settle();
    std::vector<VisibleVoxel> voxels;
    voxels.reserve(list_.size());
    for (const Reach& r : list_) voxels.push_back({ijkOf(r.key), r.visibility, r.rays});
    list_.clear();
    return voxels;
  }

 private:
  /// A voxel's key: its index shifted to non-negative 21-bit fields, z highest, so that keys
  /// sort by z, then y, then x.
  static constexpr int kBias = 1 << 20;
  static constexpr std::uint64_t kField = (std::uint64_t{1} << 21) - 1;
  static constexpr std::uint64_t kNone = ~std::uint64_t{0};  // no voxel's key: bit 63 is never set
  static constexpr int kRecentBits = 14;                       // 16,384 entries of 24 bytes: in L2

  struct Reach {
    std::uint64_t key = kNone;
    double visibility = 0.0;
    std::uint32_t rays = 0;
  };

  static bool byKey(const Reach& a, const Reach& b) { return a.key < b.key; }

  static std::uint64_t keyOf(const Index3& ijk) {
    return (std::uint64_t(ijk.z() + kBias) << 42) | (std::uint64_t(ijk.y() + kBias) << 21) |
           std::uint64_t(ijk.x() + kBias);
  }
  static Index3 ijkOf(std::uint64_t key) {
    return {static_cast<int>(key & kField) - kBias, static_cast<int>((key >> 21) & kField) - kBias,
            static_cast<int>(key >> 42) - kBias};
  }

  /// Sorts `reaches` by key and folds the entries of one voxel into one: the greatest
  /// visibility, the rays added.
  static void fold(std::vector<Reach>& reaches) {
    std::sort(reaches.begin(), reaches.end(), byKey);
    foldSorted(reaches);
  }

  /// Folds the entries of one voxel of `reaches`, in key order, into one.
  static void foldSorted(std::vector<Reach>& reaches) {
    std::size_t kept = 0;
    for (const Reach& r : reaches) {
      if (kept > 0 && reaches[kept - 1].key == r.key) {
        Reach& into = reaches[kept - 1];
        into.visibility = std::max(into.visibility, r.visibility);
        into.rays += r.rays;
      } else {
        reaches[kept++] = r;
      }
    }
    reaches.resize(kept);
  }

  void keep(const Reach& r) {
    list_.push_back(r);
    folded_ = false;
    if (list_.size() >= fold_at_) {
      fold(list_);
      fold_at_ = std::max(fold_at_, 2 * list_.size());
    }
  }

  /// Moves the table's entries to the list.
  void flush() {
    for (Reach& slot : recent_) {
      if (slot.key != kNone) keep(slot);
      slot = Reach{};
    }
  }

  std::vector<Reach> recent_;
  std::vector<Reach> list_;
  bool folded_ = true;  ///< the list holds each voxel once, in key order
  std::size_t fold_at_;
};

}  // namespace nbv::ig::detail
