// foveal/util/stats.h — small statistics for benchmarks and summaries.
#pragma once

#include <algorithm>
#include <limits>
#include <vector>

namespace foveal {

// Median (mean of the middle two for an even count); 0 for no values.
inline double median(std::vector<double> v) {
  if (v.empty()) return 0;
  std::sort(v.begin(), v.end());
  const size_t m = v.size() / 2;
  return v.size() % 2 ? v[m] : 0.5 * (v[m - 1] + v[m]);
}

// The q-quantile (0 ≤ q ≤ 1) by linear interpolation between the sorted values, NaNs left out;
// NaN for no values.
inline double quantile(std::vector<double> v, double q) {
  v.erase(std::remove_if(v.begin(), v.end(), [](double x) { return x != x; }), v.end());
  if (v.empty()) return std::numeric_limits<double>::quiet_NaN();
  std::sort(v.begin(), v.end());
  const double x = std::clamp(q, 0.0, 1.0) * static_cast<double>(v.size() - 1);
  const size_t lo = static_cast<size_t>(x), hi = std::min(lo + 1, v.size() - 1);
  return v[hi] == v[lo] ? v[lo] : v[lo] + (x - static_cast<double>(lo)) * (v[hi] - v[lo]);
}

}  // namespace foveal
