// foveal/util/stats.h — small statistics for benchmarks and summaries.
#pragma once

#include <algorithm>
#include <vector>

namespace foveal {

// Median (mean of the middle two for an even count); 0 for no values.
inline double median(std::vector<double> v) {
  if (v.empty()) return 0;
  std::sort(v.begin(), v.end());
  const size_t m = v.size() / 2;
  return v.size() % 2 ? v[m] : 0.5 * (v[m - 1] + v[m]);
}

}  // namespace foveal
