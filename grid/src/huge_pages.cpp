#include "nbv/grid/huge_pages.hpp"

#include <sys/mman.h>

#include <cstdlib>

namespace nbv::grid {

void* allocateLarge(std::size_t bytes) {
  if (bytes < kHugePageBytes) {
    void* block = std::malloc(bytes == 0 ? 1 : bytes);
    if (block == nullptr) throw std::bad_alloc();
    return block;
  }
  const std::size_t rounded = (bytes + kHugePageBytes - 1) / kHugePageBytes * kHugePageBytes;
  void* block = std::aligned_alloc(kHugePageBytes, rounded);
  if (block == nullptr) throw std::bad_alloc();
#ifdef MADV_HUGEPAGE
  madvise(block, rounded, MADV_HUGEPAGE);  // advice only: without huge pages the block still works
#endif
  return block;
}

void freeLarge(void* block) noexcept { std::free(block); }

}  // namespace nbv::grid
