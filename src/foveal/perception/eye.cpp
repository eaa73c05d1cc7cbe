// foveal/perception/eye.cpp — thin-lens eye model.
#include "foveal/perception/eye.h"

#include "foveal/util/error.h"
#include "foveal/util/parse.h"

#include <algorithm>
#include <cmath>
#include <limits>
#include <sstream>

namespace foveal {

namespace {

double number(const std::string& preset, const std::string& text) { return parse_numbers(fmt::format("eye '{}'", preset), text, 1)[0]; }

}  // namespace

EyeParams parse_eye_preset(const std::string& text) {
  EyeParams eye;
  eye.preset = text;
  if (text.empty())
    fail("eye: empty preset (expected healthy, glaucoma[:S], myopia:-D, hyperopia:+D, presbyopia:AGE, astigmatism:CYL[@AXIS])");
  // '+' joins presets; a sign right after ':' ("hyperopia:+2") belongs to the number
  std::string joined = text;
  for (size_t at = joined.find(":+"); at != std::string::npos; at = joined.find(":+")) joined.erase(at + 1, 1);
  std::stringstream parts(joined);
  std::string part;
  while (std::getline(parts, part, '+')) {
    const auto colon = part.find(':');
    const std::string name = part.substr(0, colon), value = colon == std::string::npos ? "" : part.substr(colon + 1);
    if (name == "healthy" && value.empty()) continue;
    if (name == "glaucoma") {
      eye.glaucoma = value.empty() ? 0.5 : number(text, value);
    } else if (name == "myopia") {
      const double d = number(text, value);
      eye.refraction_d = -std::abs(d);  // "myopia:3" and "myopia:-3" both mean −3 D
    } else if (name == "hyperopia") {
      if (value.empty()) fail("eye: '{}': hyperopia needs dioptres, e.g. hyperopia:2", text);
      eye.refraction_d = std::abs(number(text, value));
    } else if (name == "presbyopia") {
      eye.age_years = number(text, value);
    } else if (name == "astigmatism") {
      const auto at = value.find('@');
      eye.cylinder_d = std::abs(number(text, value.substr(0, at)));
      if (at != std::string::npos) eye.cylinder_axis_deg = number(text, value.substr(at + 1));
    } else {
      fail(
          "eye: unknown preset '{}' in '{}' (expected healthy, glaucoma[:S], myopia:-D, hyperopia:D, presbyopia:AGE, "
          "astigmatism:CYL[@AXIS])",
          name, text);
    }
  }
  validate(eye);
  return eye;
}

void validate(const EyeParams& e) {
  if (!(e.pupil_diameter_mm > 0 && e.pupil_diameter_mm <= 10))
    fail("pupil_diameter_mm: must be in (0, 10] mm, got {}", e.pupil_diameter_mm);
  if (!(e.image_distance_mm > 0 && e.image_distance_mm <= 50))
    fail("image_distance_mm: must be in (0, 50] mm, got {}", e.image_distance_mm);
  if (!(std::abs(e.refraction_d) <= 30)) fail("eye: refraction must be within ±30 D, got {}", e.refraction_d);
  if (!(e.age_years >= 0 && e.age_years <= 120)) fail("eye: age must be in [0, 120] years, got {}", e.age_years);
  if (!(e.cylinder_d >= 0 && e.cylinder_d <= 10)) fail("eye: cylinder must be in [0, 10] D, got {}", e.cylinder_d);
  if (!std::isfinite(e.cylinder_axis_deg)) fail("eye: astigmatism axis must be a number of degrees");
  if (!(e.glaucoma >= 0 && e.glaucoma <= 1)) fail("eye: glaucoma severity must be in [0, 1], got {}", e.glaucoma);
}

double accommodation_amplitude_d(double age) { return std::max(0.0, 18.5 - 0.3 * age); }

double FocusRange::far_point_m() const { return far_vergence > 0 ? 1.0 / far_vergence : std::numeric_limits<double>::infinity(); }

double FocusRange::near_point_m() const { return near_vergence > 0 ? 1.0 / near_vergence : std::numeric_limits<double>::infinity(); }

FocusRange focus_range(const EyeParams& e) {
  // A myope (refraction −M) is focused at vergence M when relaxed; a hyperope (+H) at −H.
  FocusRange r;
  r.far_vergence = -e.refraction_d;
  r.near_vergence = r.far_vergence + accommodation_amplitude_d(e.age_years);
  return r;
}

double accommodate(const EyeParams& e, double distance_m) {
  const FocusRange r = focus_range(e);
  // With astigmatism the eye puts the circle of least confusion (between the two line foci) on the target
  const double wanted = (distance_m > 0 && std::isfinite(distance_m) ? 1.0 / distance_m : 0.0) - 0.5 * e.cylinder_d;
  return std::clamp(wanted, r.far_vergence, r.near_vergence);
}

double coc_angle_rad(const EyeParams& e, double distance_m, double focus_vergence) {
  const double object_vergence = distance_m > 0 && std::isfinite(distance_m) ? 1.0 / distance_m : 0.0;
  return e.pupil_diameter_mm * 1e-3 * std::abs(object_vergence - focus_vergence);
}

glm::dvec2 coc_axes_rad(const EyeParams& e, double distance_m, double focus_vergence) {
  const double object_vergence = distance_m > 0 && std::isfinite(distance_m) ? 1.0 / distance_m : 0.0;
  const double a = e.pupil_diameter_mm * 1e-3;
  return {a * std::abs(object_vergence - focus_vergence), a * std::abs(object_vergence - focus_vergence - e.cylinder_d)};
}

double coc_retina_mm(const EyeParams& e, double distance_m, double focus_vergence) {
  return coc_angle_rad(e, distance_m, focus_vergence) * e.image_distance_mm;
}

double peripheral_penalty_per_deg(const EyeParams& e) { return 0.02 + 0.1 * e.glaucoma; }

}  // namespace foveal
