// foveal/perception/foveation.cpp — display geometry, eccentricity, acuity and the AO budget.
#include "foveal/perception/foveation.h"

#include "foveal/util/error.h"

#include <algorithm>
#include <cmath>
#include <numbers>
#include <sstream>
#include <vector>

namespace foveal {

Display parse_display(const std::string& text, Display defaults) {
  std::vector<double> values;
  std::stringstream stream(text);
  std::string item;
  while (std::getline(stream, item, ',')) {
    try {
      size_t used = 0;
      values.push_back(std::stod(item, &used));
      if (used != item.size()) throw std::invalid_argument(item);
    } catch (const std::exception&) {
      fail("display: '{}' is not a number (expected W_CM,H_CM,DIST_CM[,RES_X,RES_Y])", item);
    }
  }
  if (values.size() != 3 && values.size() != 5)
    fail("display: expected 3 or 5 comma-separated values W_CM,H_CM,DIST_CM[,RES_X,RES_Y], got {}", values.size());
  Display d = defaults;
  d.width_cm = values[0];
  d.height_cm = values[1];
  d.distance_cm = values[2];
  if (values.size() == 5) {
    if (values[3] != std::floor(values[3]) || values[4] != std::floor(values[4]) || values[3] > 1e6 || values[4] > 1e6 || values[3] < 1 ||
        values[4] < 1)
      fail("display: resolution {}x{} must be whole pixels between 1 and 1000000", values[3], values[4]);
    d.res_x = static_cast<int>(values[3]);
    d.res_y = static_cast<int>(values[4]);
  }
  validate(d);
  return d;
}

void validate(const Display& d) {
  if (!(d.width_cm > 0) || !std::isfinite(d.width_cm)) fail("display width must be a finite number > 0 cm, got {}", d.width_cm);
  if (!(d.height_cm > 0) || !std::isfinite(d.height_cm)) fail("display height must be a finite number > 0 cm, got {}", d.height_cm);
  if (!(d.distance_cm > 0) || !std::isfinite(d.distance_cm)) fail("viewing distance must be a finite number > 0 cm, got {}", d.distance_cm);
  if (d.res_x < 1 || d.res_y < 1) fail("display resolution must be at least 1x1, got {}x{}", d.res_x, d.res_y);
}

double field_of_view_x_deg(const Display& d) { return 2.0 * std::atan(d.width_cm / (2.0 * d.distance_cm)) * kDeg; }
double field_of_view_y_deg(const Display& d) { return 2.0 * std::atan(d.height_cm / (2.0 * d.distance_cm)) * kDeg; }
double pixels_per_degree(const Display& d) { return d.res_x / field_of_view_x_deg(d); }
double max_display_cpd(const Display& d) { return pixels_per_degree(d) / 2.0; }

FoveationModel::FoveationModel(const Display& display, int w, int h, glm::dvec2 gaze_px, const FoveationParams& params)
    : display_(display), width_(w), height_(h), params_(params) {
  validate(display_);
  if (w < 1 || h < 1) fail("render size must be at least 1x1, got {}x{}", w, h);
  max_cpd_ = max_display_cpd(display_);
  foveal_cpd_ = acuity_cutoff_cpd(0.0, max_cpd_);
  // Gaze ray and the axes of its tangent plane: horizontal (no y), vertical (screen down)
  gaze_dir_ = glm::normalize(eye_ray(gaze_px.x, gaze_px.y));
  horiz_ = glm::normalize(glm::cross(glm::dvec3(0, 1, 0), gaze_dir_));
  vert_ = glm::cross(gaze_dir_, horiz_);
  gaze_dir_f_ = glm::vec3(gaze_dir_);
  horiz_f_ = glm::vec3(horiz_);
  vert_f_ = glm::vec3(vert_);
}

// One definition, compiled with the flags that let its loops vectorise (src/foveal/CMakeLists.txt)
void FoveationModel::evaluate_directions_fast(const float* px, const float* py, const float* pz, size_t n, float* effective_deg,
                                              float* quality, uint16_t* rays, float* blend) const {
  const glm::vec3 g = gaze_dir_f_, h = horiz_f_, v = vert_f_;
  const float a = static_cast<float>(params_.ellipse_ratio), inv_a2 = 1.0f / (a * a), outside = 1.0f / a;
  const float deg = static_cast<float>(kDeg), e2 = static_cast<float>(kAcuityE2Deg);
  // q = min(max_cpd, F·e2 / (e2 + E)) / F₀: one division per pixel
  const float numerator = static_cast<float>(kAcuityFovealCpd * kAcuityE2Deg / foveal_cpd_);
  const float q_max = static_cast<float>(max_cpd_ / foveal_cpd_);
  for (size_t i = 0; i < n; ++i) {
    const glm::vec3 r(px[i], py[i], pz[i]);
    const float cx = g.y * r.z - g.z * r.y, cy = g.z * r.x - g.x * r.z, cz = g.x * r.y - g.y * r.x;
    const float angle = fast_atan2_positive(std::sqrt(cx * cx + cy * cy + cz * cz), g.x * r.x + g.y * r.y + g.z * r.z) * deg;
    const float ph = h.x * r.x + h.y * r.y + h.z * r.z, pv = v.x * r.x + v.y * r.y + v.z * r.z;
    const float len2 = ph * ph + pv * pv;
    const float stretch = len2 > 0 ? std::sqrt((ph * ph * inv_a2 + pv * pv) / len2) : outside;
    const float e = angle * stretch;
    effective_deg[i] = e;
    quality[i] = std::min(q_max, numerator / (e2 + std::max(0.0f, e)));
  }
  // n(E) and b(E) from q: the defaults (γ = 2, β = 0) without pow()
  const float span = static_cast<float>(params_.max_rays - params_.min_rays);
  const int min_rays = params_.min_rays;
  if (params_.gamma == 2.0) {
    for (size_t i = 0; i < n; ++i) {
      const float q = std::min(std::max(quality[i], 0.0f), 1.0f);
      rays[i] = static_cast<uint16_t>(min_rays + static_cast<int>(span * q * q + 0.5f));
    }
  } else {
    for (size_t i = 0; i < n; ++i) rays[i] = static_cast<uint16_t>(ao_ray_budget(quality[i], params_));
  }
  if (!blend) return;
  if (params_.beta == 0.0) {
    for (size_t i = 0; i < n; ++i) blend[i] = rays[i] > 0 ? 1.0f : 0.0f;
  } else {
    for (size_t i = 0; i < n; ++i) blend[i] = static_cast<float>(blend_weight(quality[i], rays[i], params_));
  }
}

}  // namespace foveal
