// foveal/perception/foveation.h — display geometry, eccentricity, acuity and the AO budget.
//
// The models of DESIGN.md, "The models, exactly": the render fills a display of W×H cm viewed
// from d cm by an eye in front of the screen centre; a pixel's eccentricity is the exact angle
// between the eye rays through it and through the gaze point, made elliptical by the ratio a;
// the cut-off frequency f_c(E) of eq. 4 gives the quality q(E) = f_c(E)/f_c(0), which sets the
// AO ray count n(E) and the blend weight b(E).
#pragma once

#include "foveal/util/hd.h"
#include "foveal/util/units.h"

#include <glm/glm.hpp>

#include <algorithm>
#include <cmath>
#include <cstddef>
#include <cstdint>
#include <numbers>

#include <string>

namespace foveal {

// A physical display; the rendered image is scaled to fill it.
struct Display {
  double width_cm = 47.5;     // visible width, cm
  double height_cm = 30.0;    // visible height, cm
  double distance_cm = 60.0;  // eye to screen centre, cm
  int res_x = 1680;           // display pixels across
  int res_y = 1050;           // display pixels down
};

// Parse "W_CM,H_CM,DIST_CM[,RES_X,RES_Y]"; without a resolution, the given default is kept.
Display parse_display(const std::string& text, Display defaults = {});

// Check a display for zero or negative sizes; throws Error naming the field.
void validate(const Display& display);

// Horizontal field of view of the display, degrees.
double field_of_view_x_deg(const Display& display);
// Vertical field of view of the display, degrees.
double field_of_view_y_deg(const Display& display);
// Display pixels per degree at the screen centre: res_x / (2·atan(W/2d)).
double pixels_per_degree(const Display& display);
// Highest frequency the display can show, cycles/degree (= ppd / 2).
double max_display_cpd(const Display& display);

inline constexpr double kAcuityE2Deg = 3.118;     // eccentricity of half resolution, degrees
inline constexpr double kAcuityFovealCpd = 43.1;  // foveal cut-off, cycles/degree
// Acuity cut-off of eq. 4, cycles/degree: min(max_cpd, 43.1·E2/(E2+E)), E in degrees.
FOVEAL_HD inline double acuity_cutoff_cpd(double e_deg, double max_cpd) {
  return std::min(max_cpd, kAcuityFovealCpd * kAcuityE2Deg / (kAcuityE2Deg + std::max(0.0, e_deg)));
}

// Parameters of the foveation model (DESIGN.md defaults).
struct FoveationParams {
  double ellipse_ratio = 1.538;  // horizontal : vertical extent of the region of interest
  int max_rays = 400;            // n_max, AO rays per pixel at q = 1
  int min_rays = 0;              // n_min, AO rays per pixel far from the gaze
  double gamma = 2.0;            // exponent of q in the ray budget
  // Exponent of q in the blend weight. 0 (AO wherever a ray is cast; the constant term only where
  // n = 0) because `foveal bench quality` measured it closest to the reference and steadiest across
  // saccades at every γ and n_max, at the same speed (docs/quality.md); 1 is the papers' blend.
  double beta = 0.0;
};

// AO rays for a quality q: n_min + round((n_max − n_min)·q^γ).
FOVEAL_HD inline int ao_ray_budget(double q, const FoveationParams& p) {
  const double span = static_cast<double>(p.max_rays - p.min_rays);
  q = std::clamp(q, 0.0, 1.0);
  const double qg = p.gamma == 2.0 ? q * q : std::pow(q, p.gamma);  // the default γ without pow()
  return p.min_rays + static_cast<int>(std::lround(span * qg));
}
// Blend weight of AO against the constant ambient: q^β, and 0 where no ray is cast.
FOVEAL_HD inline double blend_weight(double q, int rays, const FoveationParams& p) {
  if (rays <= 0) return 0.0;
  q = std::clamp(q, 0.0, 1.0);
  return p.beta == 0.0 ? 1.0 : p.beta == 1.0 ? q : std::pow(q, p.beta);
}

// atan2(y, x) for y ≥ 0, x > 0 (an angle below 90°, as between two rays through one screen) from
// Abramowitz & Stegun's 4.4.47 polynomial for atan on [0, 1] (|error| ≤ 1e-5 rad, 6e-4°), with
// atan t = π/2 − atan(1/t) above 1: no library call, so a loop over pixels vectorises.
FOVEAL_HD inline float fast_atan2_positive(float y, float x) {
  const bool swap = y > x;
  const float t = std::min(x, y) / std::max(x, y);  // one division, no branch: loops over pixels vectorise
  const float t2 = t * t;
  const float a = t * (0.9998660f + t2 * (-0.3302995f + t2 * (0.1801410f + t2 * (-0.0851330f + t2 * 0.0208351f))));
  return swap ? 1.57079633f - a : a;
}

// Per-pixel result of the foveation model.
struct FoveaSample {
  double ex_deg = 0;         // horizontal angular offset from the gaze, degrees
  double ey_deg = 0;         // vertical angular offset from the gaze, degrees
  double angle_deg = 0;      // exact angle between pixel and gaze eye rays, degrees
  double effective_deg = 0;  // elliptical eccentricity sqrt((Ex/a)² + Ey²), degrees
  double quality = 1;        // q(E) in [0, 1]
  int rays = 0;              // AO rays n(E)
  double blend = 1;          // b(E) in [0, 1]
};

// The model for one frame: display, render size and gaze; evaluate() is a pure per-pixel function,
// the same on the CPU and the GPU (the object is trivially copyable into a kernel's arguments).
class FoveationModel {
 public:
  FoveationModel(const Display& display, int render_width, int render_height, glm::dvec2 gaze_px, const FoveationParams& params);

  // Eye ray (cm, eye at origin, +z towards the screen, +y down) through a render position.
  FOVEAL_HD glm::dvec3 eye_ray(double x_px, double y_px) const {
    return {(x_px / width_ - 0.5) * display_.width_cm, (y_px / height_ - 0.5) * display_.height_cm, display_.distance_cm};
  }
  // The model at the centre of pixel (x, y).
  FOVEAL_HD FoveaSample evaluate(int x, int y) const { return evaluate_at(x + 0.5, y + 0.5); }
  // The model at a render position (pixel centres are at +0.5).
  FOVEAL_HD FoveaSample evaluate_at(double x_px, double y_px) const { return evaluate_direction(glm::normalize(eye_ray(x_px, y_px))); }
  // The model for a unit eye ray `p` (the normalised eye_ray() of a render position): callers that
  // evaluate many gazes over the same pixels keep the rays.
  FOVEAL_HD FoveaSample evaluate_direction(const glm::dvec3& p) const {
    FoveaSample s;
    // Exact angle between the two eye rays, split along the gaze's tangent-plane axes
    const double angle = std::atan2(glm::length(glm::cross(gaze_dir_, p)), glm::dot(gaze_dir_, p));
    const double ph = glm::dot(p, horiz_), pv = glm::dot(p, vert_);
    const double len = std::hypot(ph, pv);
    const double c = len > 0 ? ph / len : 1.0, sn = len > 0 ? pv / len : 0.0;
    s.angle_deg = angle * kDeg;
    s.ex_deg = s.angle_deg * c;
    s.ey_deg = s.angle_deg * sn;
    // Elliptical region of interest, acuity, budget and blend
    const double a = params_.ellipse_ratio;
    s.effective_deg = std::sqrt((s.ex_deg / a) * (s.ex_deg / a) + s.ey_deg * s.ey_deg);
    s.quality = acuity_cutoff_cpd(s.effective_deg, max_cpd_) / foveal_cpd_;
    s.rays = ao_ray_budget(s.quality, params_);
    s.blend = blend_weight(s.quality, s.rays, params_);
    return s;
  }

  // The same model in single precision for n unit eye rays at once (the normalised eye_ray()s of
  // the pixels, as three arrays x, y, z): the real-time loop's maps, evaluated whenever the gaze
  // moves. Plain loops over arrays with no library call, which the compiler vectorises
  // (foveation.cpp): 1.8 ms for 840×525 on two cores, against 7.8 ms one pixel at a time (a 2-core
  // AMD EPYC VM). E agrees with evaluate_direction within 2e-3° and q within 1e-4, so n(E) differs
  // by one ray where n_max·q^γ lies that close to a half-integer: under one pixel in a hundred
  // (foveation_test.cpp). `blend` may be null.
  void evaluate_directions_fast(const float* px, const float* py, const float* pz, size_t n, float* effective_deg, float* quality,
                                uint16_t* rays, float* blend) const;

  double max_cpd() const { return max_cpd_; }
  // The effective eccentricity up to which q = 1, degrees: 0 where the display resolves the
  // fovea's acuity (q falls from the gaze on), else where acuity falls to the display's limit
  double fovea_reach_deg() const { return foveal_cpd_ < kAcuityFovealCpd ? kAcuityE2Deg * (kAcuityFovealCpd / foveal_cpd_ - 1.0) : 0.0; }
  const FoveationParams& params() const { return params_; }

 private:
  Display display_;
  int width_, height_;
  FoveationParams params_;
  double max_cpd_, foveal_cpd_;
  glm::dvec3 gaze_dir_, horiz_, vert_;       // unit gaze ray and its tangent-plane axes
  glm::vec3 gaze_dir_f_, horiz_f_, vert_f_;  // the same in single precision (evaluate_directions_fast)
};

}  // namespace foveal
