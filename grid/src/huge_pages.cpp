#include "nbv/grid/huge_pages.hpp"

#include <sys/mman.h>

#include <algorithm>
#include <cstdlib>
#include <mutex>
#include <vector>

namespace nbv::grid {

namespace {

std::size_t roundedLarge(std::size_t bytes) { return (bytes + kHugePageBytes - 1) / kHugePageBytes * kHugePageBytes; }

/// Freed large blocks, oldest first, with their rounded sizes.
struct KeptBlocks {
  struct Block {
    void* data;
    std::size_t bytes;
  };
  /// Room for this many, reserved once: a free never allocates.
  static constexpr std::size_t kMaxBlocks = 64;

  KeptBlocks() { blocks.reserve(kMaxBlocks); }

  std::mutex mutex;
  std::vector<Block> blocks;
  std::size_t bytes = 0;
};

/// Never destroyed: a static object's array may be freed after any other static is gone.
KeptBlocks& kept() {
  static auto* const blocks = new KeptBlocks;
  return *blocks;
}

}  // namespace

void* allocateLarge(std::size_t bytes) {
  if (bytes < kHugePageBytes) {
    void* block = std::malloc(bytes == 0 ? 1 : bytes);
    if (block == nullptr) throw std::bad_alloc();
    return block;
  }
  const std::size_t rounded = roundedLarge(bytes);
  {
    // The smallest kept block that holds `rounded` with at most half as much again: a larger
    // one is left for a larger array.
    KeptBlocks& k = kept();
    const std::lock_guard<std::mutex> lock(k.mutex);
    auto best = k.blocks.end();
    for (auto b = k.blocks.begin(); b != k.blocks.end(); ++b) {
      if (b->bytes >= rounded && b->bytes <= rounded + rounded / 2 && (best == k.blocks.end() || b->bytes < best->bytes)) best = b;
    }
    if (best != k.blocks.end()) {
      void* block = best->data;
#ifdef MADV_DONTNEED
      // The pages past the request given back: the caller frees it as a block of `rounded`
      // bytes, which is then all that is kept of it.
      if (best->bytes > rounded) madvise(static_cast<char*>(block) + rounded, best->bytes - rounded, MADV_DONTNEED);
#endif
      k.bytes -= best->bytes;
      k.blocks.erase(best);
      return block;
    }
  }
  void* block = std::aligned_alloc(kHugePageBytes, rounded);
  if (block == nullptr) throw std::bad_alloc();
#ifdef MADV_HUGEPAGE
  madvise(block, rounded, MADV_HUGEPAGE);  // advice only: without huge pages the block still works
#endif
  return block;
}

void freeLarge(void* block, std::size_t bytes) noexcept {
  if (block == nullptr || bytes < kHugePageBytes) {
    std::free(block);
    return;
  }
  const std::size_t rounded = roundedLarge(bytes);
  if (rounded > kKeptLargeBytes) {
    std::free(block);
    return;
  }
  KeptBlocks& k = kept();
  const std::lock_guard<std::mutex> lock(k.mutex);
  // The oldest given back while keeping this one too would pass either limit.
  std::size_t oldest = 0;
  for (; oldest < k.blocks.size() &&
         (k.bytes + rounded > kKeptLargeBytes || k.blocks.size() - oldest >= KeptBlocks::kMaxBlocks);
       ++oldest) {
    k.bytes -= k.blocks[oldest].bytes;
    std::free(k.blocks[oldest].data);
  }
  k.blocks.erase(k.blocks.begin(), k.blocks.begin() + static_cast<std::ptrdiff_t>(oldest));
  k.blocks.push_back({block, rounded});  // within the room reserved: no allocation
  k.bytes += rounded;
}

void giveBackLarge(void* block) noexcept { std::free(block); }

std::size_t keptLargeBytes() {
  KeptBlocks& k = kept();
  const std::lock_guard<std::mutex> lock(k.mutex);
  return k.bytes;
}

void releaseKeptLarge() {
  KeptBlocks& k = kept();
  const std::lock_guard<std::mutex> lock(k.mutex);
  for (const KeptBlocks::Block& b : k.blocks) std::free(b.data);
  k.blocks.clear();
  k.bytes = 0;
}

}  // namespace nbv::grid
