// foveal/util/sampling.cpp — the precomputed Sobol table.
#include "foveal/util/sampling.h"

#include <vector>

namespace foveal {

const uint32_t* sobol_table_2d() {
  static const std::vector<uint32_t> table = [] {
    std::vector<uint32_t> t(2 * kSobolTableSize);
    for (uint32_t k = 0; k < kSobolTableSize; ++k) {
      t[2 * k] = sobol_dim0(k);
      t[2 * k + 1] = sobol_dim1(k);
    }
    return t;
  }();
  return table.data();
}

}  // namespace foveal
