// foveal/vision/sharpness.cpp — the lazily starving voxel field.
#include "foveal/vision/sharpness.h"

#include "foveal/util/error.h"

#include <cmath>

namespace foveal {

SharpnessField::SharpnessField(const Bounds& bounds, float voxel, double starvation)
    : voxel_(voxel), starvation_(starvation), log_growth_(std::log1p(starvation)) {
  if (!(voxel > 0) || !std::isfinite(voxel)) fail("--voxel: must be a positive size, got {}", voxel);
  if (!(starvation >= 0 && starvation < 10)) fail("--starvation: must be in [0, 10), got {}", starvation);
  const glm::vec3 size = bounds.hi - bounds.lo;
  if (!(size.x >= 0 && size.y >= 0 && size.z >= 0)) fail("sharpness field: empty scene bounds");
  origin_ = bounds.lo - glm::vec3(0.5f * voxel);
  const glm::dvec3 cells = glm::ceil(glm::dvec3(size) / double(voxel)) + 1.0;
  if (cells.x * cells.y * cells.z > double(size_t(1) << 28))
    fail("--voxel: {} gives {:.0f} cells (more than 2^28); choose a larger voxel", voxel, cells.x * cells.y * cells.z);
  dims_ = glm::ivec3(cells);
  const size_t n = size_t(dims_.x) * dims_.y * dims_.z;
  coc_.assign(n, kUnseen);
  stamp_.assign(n, 0);
  written_.assign(n, 0);
  growth_.resize(4096);
  for (size_t age = 0; age < growth_.size(); ++age) growth_[age] = static_cast<float>(std::exp(log_growth_ * double(age)));
}

int64_t SharpnessField::cell(glm::vec3 p) const {
  const glm::vec3 g = (p - origin_) / voxel_;
  if (!(g.x >= 0 && g.y >= 0 && g.z >= 0)) return -1;  // also NaN
  const glm::ivec3 c(g);
  if (c.x >= dims_.x || c.y >= dims_.y || c.z >= dims_.z) return -1;
  return (int64_t(c.z) * dims_.y + c.y) * dims_.x + c.x;
}

float SharpnessField::effective(int64_t c, uint32_t step) const {
  if (c < 0 || written_[c] != epoch_) return kUnseen;
  const uint32_t age = step >= stamp_[c] ? step - stamp_[c] : 0;
  const float growth = age < growth_.size() ? growth_[age] : static_cast<float>(std::exp(log_growth_ * double(age)));
  return coc_[c] * growth;
}

float SharpnessField::effective(glm::vec3 p, uint32_t step) const { return effective(cell(p), step); }

bool SharpnessField::update(int64_t c, float coc, uint32_t step) {
  if (c < 0 || !(coc < effective(c, step))) return false;
  coc_[c] = coc;
  stamp_[c] = step;
  written_[c] = epoch_;
  return true;
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
