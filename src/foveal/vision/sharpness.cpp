// foveal/vision/sharpness.cpp — the lazily starving voxel field.
#include "foveal/vision/sharpness.h"

#include "foveal/util/error.h"

#include <cmath>

namespace foveal {

void validate_starvation(double starvation) {
  if (!(starvation >= 0 && starvation < 10)) fail("starvation: must be in [0, 10), got {}", starvation);
}

SharpnessField::SharpnessField(const Bounds& bounds, float voxel, double starvation) : starvation_(starvation) {
  if (!(voxel > 0) || !std::isfinite(voxel)) fail("voxel: must be a positive size, got {}", voxel);
  validate_starvation(starvation);
  const glm::vec3 size = bounds.hi - bounds.lo;
  if (!(size.x >= 0 && size.y >= 0 && size.z >= 0)) fail("sharpness field: empty scene bounds");
  const glm::dvec3 cells = glm::ceil(glm::dvec3(size) / double(voxel)) + 1.0;
  if (cells.x * cells.y * cells.z > double(size_t(1) << 28))
    fail("voxel: {} gives {:.0f} cells (more than 2^28); choose a larger voxel", voxel, cells.x * cells.y * cells.z);
  SharpnessFieldView& v = view_;
  v.origin = bounds.lo - glm::vec3(0.5f * voxel);
  v.voxel = voxel;
  v.dims = glm::ivec3(cells);
  v.log_growth = std::log1p(starvation);
  const size_t n = size_t(v.dims.x) * v.dims.y * v.dims.z;
  coc_.assign(n, kUnseen);
  stamp_.assign(n, 0);
  written_.assign(n, 0);
  growth_.resize(4096);
  for (size_t age = 0; age < growth_.size(); ++age) growth_[age] = static_cast<float>(std::exp(v.log_growth * double(age)));
  v.coc = coc_.data();
  v.stamp = stamp_.data();
  v.written = written_.data();
  v.growth = growth_.data();
  v.growth_size = static_cast<uint32_t>(growth_.size());
}

float default_voxel_size(const Bounds& bounds, int divisions, size_t max_cells) {
  const glm::vec3 size = bounds.hi - bounds.lo;
  float voxel = std::max(glm::length(size) / divisions, 1e-6f);
  auto count = [&](float v) {
    const glm::dvec3 c = glm::ceil(glm::dvec3(size) / double(v)) + 1.0;
    return c.x * c.y * c.z;
  };
  while (count(voxel) > double(max_cells)) voxel *= 1.25f;
  return voxel;
}

}  // namespace foveal
