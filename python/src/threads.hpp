#pragma once
// Private to the Python module: running C++ work off the GIL on a chosen number of threads.

#include "nbv/errors.hpp"

#include <pybind11/pybind11.h>
#include <tbb/task_arena.h>

#include <optional>
#include <string>
#include <utility>

namespace nbv::python {

/// \throws InvalidArgument for a thread count given and below 1.
inline void checkThreads(std::optional<int> threads) {
  if (threads && *threads < 1) throw InvalidArgument("threads " + std::to_string(*threads) + " must be at least 1");
}

/// Runs `work()` with the GIL released, in a TBB arena of `threads` threads when given, else
/// on TBB's default arena (every core). \throws InvalidArgument for threads < 1.
template <class F>
auto runReleased(std::optional<int> threads, F&& work) {
  checkThreads(threads);
  pybind11::gil_scoped_release unlocked;
  if (!threads) return work();
  tbb::task_arena arena(*threads);
  return arena.execute(std::forward<F>(work));
}

}  // namespace nbv::python
