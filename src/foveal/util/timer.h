// foveal/util/timer.h — wall-clock stopwatch in milliseconds.
#pragma once

#include <chrono>

namespace foveal {

// Starts on construction; ms() reads the elapsed time.
class Timer {
 public:
  Timer() : start_(std::chrono::steady_clock::now()) {}
  double ms() const { return std::chrono::duration<double, std::milli>(std::chrono::steady_clock::now() - start_).count(); }
  void reset() { start_ = std::chrono::steady_clock::now(); }

 private:
  std::chrono::steady_clock::time_point start_;
};

}  // namespace foveal
