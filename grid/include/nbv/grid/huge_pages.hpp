#pragma once
/// \file An allocator for the large arrays a map rebuilds often (the IG snapshot): blocks of
/// 2 MiB and more are aligned to 2 MiB and marked for transparent huge pages, so that writing
/// them the first time costs a page fault per 2 MiB rather than per 4 KiB. Faults are dear in
/// a virtual machine: with 4 KiB pages, the snapshot's first touches made an NBV decision of
/// the demo 1.5-2x slower (docs/performance-log.md, "Information gain (issue 4)").
///
/// A freed large block is kept, up to kKeptLargeBytes in all, for the next allocation of about
/// its size: the new evaluator of a sweep's next run then writes memory the process has
/// touched already instead of taking first-touch faults again (in a virtual machine a huge
/// page's first touch may cost milliseconds). releaseKeptLarge() gives them back.

#include <cstddef>
#include <new>
#include <type_traits>
#include <utility>

namespace nbv::grid {

/// Blocks below this size come from malloc as usual.
inline constexpr std::size_t kHugePageBytes = std::size_t{2} << 20;

/// `bytes` of memory, aligned to kHugePageBytes and advised as huge pages (Linux madvise,
/// where the system offers it) if at least kHugePageBytes, else from malloc. A large request
/// takes the smallest kept block that holds it with at most half as much again, if any.
/// \throws std::bad_alloc. Thread-safe.
void* allocateLarge(std::size_t bytes);
/// Frees a block of allocateLarge(`bytes`): one of at least kHugePageBytes is kept for reuse
/// while the kept blocks stay within kKeptLargeBytes (the oldest given back first). Thread-safe.
void freeLarge(void* block, std::size_t bytes) noexcept;

/// Frees a block of allocateLarge() at once, without keeping it: for an array that a larger one
/// replaced, whose size nothing is likely to ask for again. Thread-safe.
void giveBackLarge(void* block) noexcept;

/// The most bytes of freed large blocks kept for reuse.
inline constexpr std::size_t kKeptLargeBytes = std::size_t{256} << 20;
/// The bytes of freed large blocks kept now. Thread-safe.
std::size_t keptLargeBytes();
/// Gives every kept block back to the system. Thread-safe.
void releaseKeptLarge();

/// std::allocator's drop-in for large arrays (see the file comment). Stateless.
template <class T>
struct HugePageAllocator {
  using value_type = T;
  HugePageAllocator() = default;
  template <class U>
  HugePageAllocator(const HugePageAllocator<U>&) noexcept {}
  T* allocate(std::size_t n) {
    if (n > static_cast<std::size_t>(-1) / sizeof(T)) throw std::bad_alloc();
    return static_cast<T*>(allocateLarge(n * sizeof(T)));
  }
  void deallocate(T* block, std::size_t n) noexcept { freeLarge(block, n * sizeof(T)); }
  template <class U>
  bool operator==(const HugePageAllocator<U>&) const noexcept {
    return true;
  }
};

/// An array of `size` values from allocateLarge(), left unwritten, so that its first writes
/// (and the page faults they bring) may be shared among tasks. Move-only.
template <class T>
class LargeArray {
  static_assert(std::is_trivially_copyable_v<T> && std::is_trivially_destructible_v<T>);

 public:
  LargeArray() = default;
  /// \throws std::bad_alloc.
  explicit LargeArray(std::size_t size) : data_(allocate(size)), size_(size) {}
  LargeArray(LargeArray&& other) noexcept
      : data_(std::exchange(other.data_, nullptr)), size_(std::exchange(other.size_, 0)) {}
  LargeArray& operator=(LargeArray&& other) noexcept {
    if (this != &other) {
      freeLarge(data_, size_ * sizeof(T));
      data_ = std::exchange(other.data_, nullptr);
      size_ = std::exchange(other.size_, 0);
    }
    return *this;
  }
  LargeArray(const LargeArray&) = delete;
  LargeArray& operator=(const LargeArray&) = delete;
  ~LargeArray() { freeLarge(data_, size_ * sizeof(T)); }

  T* data() { return data_; }
  const T* data() const { return data_; }
  std::size_t size() const { return size_; }

  /// Empties the array, its block given back to the system rather than kept (giveBackLarge()).
  void giveBack() noexcept {
    giveBackLarge(std::exchange(data_, nullptr));
    size_ = 0;
  }

 private:
  static T* allocate(std::size_t size) { return size == 0 ? nullptr : HugePageAllocator<T>().allocate(size); }

  T* data_ = nullptr;
  std::size_t size_ = 0;
};

}  // namespace nbv::grid
