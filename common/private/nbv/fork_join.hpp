#pragma once
/// \file Fork-join edges for ThreadSanitizer across TBB's scheduler, private to the modules
/// that hand work to TBB (target nbv_fork_join; never installed). Debian's libtbb is not
/// instrumented, so TSan cannot see that a task starts after the writes that precede
/// `tbb::parallel_for` and ends before it returns; every driver that hands work to TBB marks
/// those two edges with a ForkJoin. Compiles to nothing outside TSan builds. Needs oneTBB's
/// headers (the modules that hand work to TBB link it).

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

#include <tbb/parallel_for.h>

namespace nbv {

/// Fork-join edges as static functions, on two process-wide sync addresses: a task cannot read
/// an object its spawner wrote (not even the lambda that holds a reference to one) before it
/// has acquired the fork edge. The spawning thread calls fork() after it has written all the
/// tasks read (the task lambda included: build it first) and just before handing it to TBB, and
/// joined() after TBB returns; each task calls enter() first and leave() last. For
/// parallel_reduce bodies, which TBB copies and joins on any thread, a body publishes itself
/// after each change and a thread observes a body before it reads it.
struct ForkJoin {
  static void fork() { release(&sync().fork); }
  static void enter() { acquire(&sync().fork); }
  static void leave() { release(&sync().join); }
  static void joined() { acquire(&sync().join); }
  static void publish(const void* body) { release(static_cast<const char*>(body)); }
  static void observe(const void* body) { acquire(static_cast<const char*>(body)); }

  /// tbb::parallel_for over the task indices 0 .. count - 1, with both edges marked: each task
  /// calls `task(index)` between enter() and leave(). Work is handed out by index, so no task
  /// reads TBB's range objects; build `task` before the call (the fork edge follows it).
  template <class Index, class Task>
  static void parallelFor(Index count, const Task& task) {
    const auto in_task = [&task](Index index) {
      enter();
      task(index);
      leave();
    };
    fork();  // after everything the tasks read, the lambda included
    tbb::parallel_for(Index{0}, count, in_task);
    joined();
  }

 private:
  struct Sync {
    char fork = 0;
    char join = 0;
  };
  static Sync& sync() {
    static Sync addresses;
    return addresses;
  }
#ifdef NBV_TSAN
  static void release(const char* at) { __tsan_release(const_cast<char*>(at)); }
  static void acquire(const char* at) { __tsan_acquire(const_cast<char*>(at)); }
#else
  static void release(const char*) {}
  static void acquire(const char*) {}
#endif
};

}  // namespace nbv
