// foveal/vision/retinotopy.h — where a camera's pixels lie in the visual field of an eye at the
// camera: one FOVEAL_HD rule, evaluated on the host's threads for the CPU's impairment passes and
// in a kernel for the GPU's, on the same grid of every RetinotopyGrid::kStep-th pixel.
#pragma once

#include "foveal/impair/impairments.h"
#include "foveal/render/pixel.h"
#include "foveal/util/hd.h"
#include "foveal/util/sampling.h"

#include <glm/glm.hpp>

#include <cmath>

namespace foveal {

// The eye sits at the camera and fixates the point seen at `fixation_px`. A pixel's place in the
// field is the angle between its ray and the fixation's (eccentricity), split along the directions
// of the camera's right and up in the plane tangent to the fixation's ray: degrees, x right, y up.
// ppd is the camera's pixels per degree at the image centre.
class CameraRetinotopy {
 public:
  CameraRetinotopy(const Camera& camera, int width, int height, glm::vec2 fixation_px);

  // The field position of render position (x, y) (pixel centres at +0.5). The angle comes from
  // angle_atan2 (within 0.0007° of atan2).
  FOVEAL_HD glm::vec2 operator()(double x_px, double y_px) const {
    const glm::vec3 p = rays_(x_px, y_px).dir;
    const float ph = glm::dot(p, h_), pv = glm::dot(p, v_), len = std::sqrt(ph * ph + pv * pv);
    const float angle = glm::degrees(angle_atan2(len, glm::dot(gaze_, p)));
    return len > 0 ? glm::vec2(angle * ph / len, angle * pv / len) : glm::vec2(0.0f);
  }
  // Point (i, j) of the grid: pixel (i·kStep, j·kStep)'s centre (beyond the image for the last
  // column and row, so that every pixel lies between four points).
  FOVEAL_HD glm::vec2 grid_point(int i, int j) const {
    constexpr int step = RetinotopyGrid::kStep;
    return (*this)(i * step + 0.5, j * step + 0.5);
  }

  int width() const { return width_; }
  int height() const { return height_; }
  double ppd() const { return ppd_; }
  int columns() const { return (width_ + RetinotopyGrid::kStep - 1) / RetinotopyGrid::kStep + 1; }
  int rows() const { return (height_ + RetinotopyGrid::kStep - 1) / RetinotopyGrid::kStep + 1; }
  // The grid with every point (the host's threads; expanded, within 1.5e-3° — 0.02 px — of the
  // rule at every pixel of 1280×720 with 60° of view: a test), and the grid's sizes without points
  // (a retina that is unimpaired needs none).
  RetinotopyGrid grid() const;
  RetinotopyGrid sizes() const { return {width_, height_, columns(), rows(), {}, ppd_}; }

 private:
  CameraRays rays_;
  glm::vec3 gaze_{}, h_{}, v_{};  // the fixation's ray; the tangent plane's right and up
  int width_ = 0, height_ = 0;
  double ppd_ = 1;
};

}  // namespace foveal
