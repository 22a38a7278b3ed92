#pragma once
// Private: the last few values a process built from large inputs (a ray set's walk order, its
// stratified sample), shared, so that the evaluators and deciders of a process (one per
// reconstruction) build each once.

#include <algorithm>
#include <cstddef>
#include <memory>
#include <mutex>
#include <vector>

namespace nbv::ig::detail {

/// Up to kKept values, the least recently used dropped first. Thread-safe.
template <class T, std::size_t kKept>
class RecentlyBuilt {
 public:
  /// The kept value for which `is_it(value)` holds, now the most recently used; else the one
  /// `build()` returns, kept. A build that throws keeps nothing.
  template <class IsIt, class Build>
  std::shared_ptr<const T> get(const IsIt& is_it, const Build& build) {
    const std::lock_guard lock(mutex_);
    for (auto it = kept_.rbegin(); it != kept_.rend(); ++it) {
      if (is_it(**it)) {
        std::rotate(it.base() - 1, it.base(), kept_.end());
        return kept_.back();
      }
    }
    std::shared_ptr<const T> value = build();
    if (kept_.size() == kKept) kept_.erase(kept_.begin());
    kept_.push_back(value);
    return value;
  }

 private:
  std::mutex mutex_;
  std::vector<std::shared_ptr<const T>> kept_;  ///< the most recently used last
};

}  // namespace nbv::ig::detail
