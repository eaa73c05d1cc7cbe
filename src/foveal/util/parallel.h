// foveal/util/parallel.h — the thread count of a run (oneTBB).
#pragma once

#include <tbb/global_control.h>
#include <tbb/info.h>

#include <memory>

namespace foveal {

// A run's thread count: `threads`, or where it is 0 all the cores this process may use.
inline int thread_count(int threads) { return threads > 0 ? threads : tbb::info::default_concurrency(); }

// Limits oneTBB to `threads` workers while alive (0 = all cores).
class ThreadScope {
 public:
  explicit ThreadScope(int threads)
      : threads_(thread_count(threads)),
        control_(std::make_unique<tbb::global_control>(tbb::global_control::max_allowed_parallelism, threads_)) {}
  int threads() const { return threads_; }

 private:
  int threads_;
  std::unique_ptr<tbb::global_control> control_;
};

}  // namespace foveal
