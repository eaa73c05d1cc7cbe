// foveal/vision/coc.h — one pixel's circle of confusion at one step, written once for the CPU
// simulation (simulate.cpp) and the GPU's kernels.
#pragma once

#include "foveal/util/hd.h"
#include "foveal/util/sampling.h"

#include <glm/glm.hpp>

#include <cmath>

namespace foveal {

// The CoC (visual angle, degrees) of the ellipse's larger diameter, and the two diameters as
// fractions of it (along, across the cylinder axis; both 1 for a round CoC).
struct PixelCoc {
  float major_deg = 0;
  glm::vec2 scale{1.0f};
};

// The eye at the camera, accommodated to `focus` dioptres: A·|1/D − v| (+ the peripheral penalty
// × eccentricity) along the cylinder axis, A·|1/D − v − C| (+ the same) across it. Distances are
// along the optical axis (a thin lens focuses planes); eccentricity is the angle between the
// pixel's camera ray and the fixation's. Single precision: vergences of a few dioptres, degrees.
struct CocModel {
  glm::vec3 axis{0, 0, -1};      // the camera's viewing direction, unit
  glm::vec3 gaze_dir{0, 0, -1};  // the camera ray through the fixation, unit
  float metres_per_unit = 1;
  float focus_vergence = 0;   // dioptres
  float pupil_deg = 0;        // pupil diameter in radians, in degrees (A)
  float penalty_per_deg = 0;  // degrees of CoC per degree of eccentricity
  float cylinder = 0;         // dioptres; 0 = round CoCs
  bool astigmatic = false;

  // `depth` is the hit distance along the unit ray `view` (ignored without a hit).
  FOVEAL_HD PixelCoc operator()(bool hit, float depth, glm::vec3 view) const {
    const float axial_m = hit ? depth * glm::dot(view, axis) * metres_per_unit : 0.0f;
    const float object_vergence = axial_m > 0 ? 1.0f / axial_m : 0.0f;
    const float ecc = glm::degrees(angle_atan2(glm::length(glm::cross(view, gaze_dir)), glm::dot(view, gaze_dir)));
    const float along = pupil_deg * std::abs(object_vergence - focus_vergence) + penalty_per_deg * ecc;
    PixelCoc c;
    if (!astigmatic) {
      c.major_deg = along;
      return c;
    }
    const float across = pupil_deg * std::abs(object_vergence - focus_vergence - cylinder) + penalty_per_deg * ecc;
    c.major_deg = std::max(along, across);
    if (c.major_deg > 0) c.scale = glm::vec2(along / c.major_deg, across / c.major_deg);
    return c;
  }
};

}  // namespace foveal
