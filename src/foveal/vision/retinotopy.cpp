// foveal/vision/retinotopy.cpp — the host's side of CameraRetinotopy.
#include "foveal/vision/retinotopy.h"

#include "foveal/vision/thin_lens.h"

#include <tbb/parallel_for.h>

namespace foveal {

CameraRetinotopy::CameraRetinotopy(const Camera& camera, int width, int height, glm::vec2 fixation_px)
    : rays_(camera, width, height), width_(width), height_(height), ppd_(camera_pixels_per_degree(camera, height)) {
  gaze_ = rays_(fixation_px.x, fixation_px.y).dir;
  const glm::vec3 forward = glm::normalize(camera.look - camera.eye);
  const glm::vec3 right = glm::normalize(glm::cross(forward, camera.up));
  h_ = glm::normalize(right - glm::dot(right, gaze_) * gaze_);
  v_ = glm::normalize(glm::cross(h_, gaze_));
}

RetinotopyGrid CameraRetinotopy::grid() const {
  RetinotopyGrid r = sizes();
  r.field_deg.resize(static_cast<size_t>(r.columns) * r.rows);
  tbb::parallel_for(0, r.rows, [&](int j) {
    for (int i = 0; i < r.columns; ++i) r.field_deg[static_cast<size_t>(j) * r.columns + i] = grid_point(i, j);
  });
  return r;
}

}  // namespace foveal
