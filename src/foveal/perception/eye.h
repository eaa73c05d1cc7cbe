// foveal/perception/eye.h — the thin-lens eye of the vision simulation: accommodation, the
// reachable focus of healthy, ametropic and presbyopic eyes, the circle of confusion, glaucoma.
//
// Focus is handled as a vergence (dioptres, 1/m). An eye can focus on object vergences in
// [v_far, v_far + amplitude]: an emmetrope from 0 (infinity) to its accommodation amplitude;
// a myope of −M D from M (far point 1/M m); a hyperope of +H D from −H (accommodation spent
// to see infinity). The circle of confusion of a point at D metres, focused at vergence v, is
// the visual angle A·|1/D − v| radians (A = pupil diameter in metres; DESIGN.md, Demers' thin
// lens with the image distance cancelled).
#pragma once

#include <glm/glm.hpp>

#include <string>

namespace foveal {

struct EyeParams {
  double pupil_diameter_mm = 3.5;   // A (the paper's 3.5 mm, read as a diameter)
  double image_distance_mm = 25.0;  // I, lens to retina (only for the retinal CoC in mm)
  double refraction_d = 0;          // spherical error: −M (myopia) … +H (hyperopia), dioptres
  double age_years = 25;            // sets the accommodation amplitude (Hofstetter's average)
  double cylinder_d = 0;            // astigmatism: cylinder power, dioptres (≥ 0)
  double cylinder_axis_deg = 0;     // astigmatism: axis, degrees (0 = horizontal)
  double glaucoma = 0;              // severity in [0, 1]; 0 = healthy
  std::string preset = "healthy";   // the name it was made from
};

// "healthy", "glaucoma[:SEVERITY]", "myopia:-3", "hyperopia:+2", "presbyopia:AGE",
// "astigmatism:CYL[@AXIS]"; several joined with '+' (e.g. "presbyopia:60+myopia:-2").
// Throws Error naming the preset.
EyeParams parse_eye_preset(const std::string& text);
void validate(const EyeParams& eye);

// Average amplitude of accommodation at an age, dioptres: Hofstetter's 18.5 − 0.3·age, ≥ 0.
double accommodation_amplitude_d(double age_years);

// The object vergences (1/m) the eye can focus on: [far, near].
struct FocusRange {
  double far_vergence = 0;      // 1/far point; may be negative (hyperopia beyond the amplitude)
  double near_vergence = 0;     // 1/near point
  double far_point_m() const;   // infinity when far_vergence ≤ 0
  double near_point_m() const;  // infinity when near_vergence ≤ 0
};
FocusRange focus_range(const EyeParams& eye);

// The vergence the eye accommodates to when it wants to focus at `distance_m` (clamped); with a
// cylinder C, at 1/distance − C/2, which puts the circle of least confusion on the target.
double accommodate(const EyeParams& eye, double distance_m);

// Circle of confusion of a point at `distance_m` with the eye focused at vergence `focus_vergence`,
// as a visual angle in radians: A·|1/D − v|.
double coc_angle_rad(const EyeParams& eye, double distance_m, double focus_vergence);
// Astigmatism: the blur ellipse's diameters (radians) along the cylinder axis, A·|1/D − v|, and
// across it, A·|1/D − v − C|; the two are equal without a cylinder.
glm::dvec2 coc_axes_rad(const EyeParams& eye, double distance_m, double focus_vergence);
// The same on the retina, mm: A·I·|1/D − v|.
double coc_retina_mm(const EyeParams& eye, double distance_m, double focus_vergence);

// Glaucoma's and the healthy eye's peripheral penalty: extra CoC (degrees) per degree of
// eccentricity from the fixation: 0.02 for a healthy eye (0.4° of blur 20° out), plus
// 0.1 × the glaucoma severity.
double peripheral_penalty_per_deg(const EyeParams& eye);

}  // namespace foveal
