#pragma once
/// \file Fork-join edges for ThreadSanitizer across TBB's scheduler. Debian's libtbb is not
/// instrumented, so TSan cannot see that a task starts after the writes that precede
/// `tbb::parallel_for` and ends before it returns; every driver that hands work to TBB marks
/// those two edges with a ForkJoin. Compiles to nothing outside TSan builds.

#if defined(__SANITIZE_THREAD__)
#define NBV_TSAN 1
#elif defined(__has_feature)
#if __has_feature(thread_sanitizer)
#define NBV_TSAN 1
#endif
#endif

#ifdef NBV_TSAN
#include <sanitizer/tsan_interface.h>
#endif

namespace nbv::kernels {

/// One fork-join region. The spawning thread calls fork() before handing work to TBB and
/// joined() after TBB returns; each task calls enter() first and leave() last (for
/// parallel_reduce bodies: in the splitting constructor enter(), in join() joined() then
/// leave()). Two separate sync addresses, so tasks gain no edges from each other.
class ForkJoin {
 public:
  void fork() const { release(&fork_); }
  void enter() const { acquire(&fork_); }
  void leave() const { release(&join_); }
  void joined() const { acquire(&join_); }
  /// For parallel_reduce bodies, which TBB copies and joins on any thread: a body publishes
  /// itself after each change, and a thread observes a body before it reads it.
  static void publish(const void* body) { release(static_cast<const char*>(body)); }
  static void observe(const void* body) { acquire(static_cast<const char*>(body)); }

 private:
#ifdef NBV_TSAN
  static void release(const char* sync) { __tsan_release(const_cast<char*>(sync)); }
  static void acquire(const char* sync) { __tsan_acquire(const_cast<char*>(sync)); }
#else
  static void release(const char*) {}
  static void acquire(const char*) {}
#endif
  char fork_ = 0;
  char join_ = 0;
};

}  // namespace nbv::kernels
