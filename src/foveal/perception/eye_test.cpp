// The thin-lens eye: CoC at known distances, the reachable focus of ametropic and presbyopic eyes.
#include "foveal/perception/eye.h"
#include "foveal/util/error.h"

#include <gtest/gtest.h>

#include <cmath>

using namespace foveal;

TEST(Eye, CocFollowsTheThinLensAtKnownDistances) {
  EyeParams eye;  // A = 3.5 mm
  // Focused at 2 m, a point at 1 m: A·|1/1 − 1/2| = 3.5e-3 × 0.5 rad
  EXPECT_NEAR(coc_angle_rad(eye, 1.0, 1.0 / 2.0), 1.75e-3, 1e-12);
  EXPECT_NEAR(coc_angle_rad(eye, 2.0, 0.5), 0.0, 1e-15);           // in focus
  EXPECT_NEAR(coc_angle_rad(eye, INFINITY, 0.5), 1.75e-3, 1e-12);  // infinity: vergence 0
  EXPECT_NEAR(coc_retina_mm(eye, 1.0, 0.5), 1.75e-3 * 25.0, 1e-12);
  // Demers' form |A·F·(P − D) / (D·(P − F))| with 1/F = 1/P + 1/I, as in the paper: the same
  // retinal blur up to the small-angle step I ≈ F
  const double P = 2.0, D = 1.0, I = 0.025, A = 3.5e-3, F = 1.0 / (1.0 / P + 1.0 / I);
  EXPECT_NEAR(std::abs(A * F * (P - D) / (D * (P - F))) * 1000, coc_retina_mm(eye, D, 1 / P), 0.002);
  // Linear in the pupil diameter
  eye.pupil_diameter_mm = 7;
  EXPECT_NEAR(coc_angle_rad(eye, 1.0, 0.5), 3.5e-3, 1e-12);
}

TEST(Eye, AmetropiaAndPresbyopiaClampTheFocus) {
  const EyeParams young = parse_eye_preset("healthy");
  EXPECT_NEAR(focus_range(young).near_point_m(), 1.0 / (18.5 - 0.3 * 25), 1e-12);
  EXPECT_TRUE(std::isinf(focus_range(young).far_point_m()));
  EXPECT_DOUBLE_EQ(accommodate(young, 0.3), 1.0 / 0.3);  // reachable: exact focus
  // Myopia −3 D cannot focus beyond 1/3 m
  const EyeParams myope = parse_eye_preset("myopia:-3");
  EXPECT_NEAR(focus_range(myope).far_point_m(), 1.0 / 3.0, 1e-12);
  EXPECT_DOUBLE_EQ(accommodate(myope, 10.0), 3.0);
  EXPECT_GT(coc_angle_rad(myope, 10.0, accommodate(myope, 10.0)), 3.5e-3 * 2.8);
  EXPECT_NEAR(coc_angle_rad(myope, 0.25, accommodate(myope, 0.25)), 0.0, 1e-15);  // near is fine
  // Presbyopia at 60 (amplitude 0.5 D) cannot focus at 30 cm
  const EyeParams old = parse_eye_preset("presbyopia:60");
  EXPECT_NEAR(accommodation_amplitude_d(60), 0.5, 1e-12);
  EXPECT_NEAR(focus_range(old).near_point_m(), 2.0, 1e-12);
  EXPECT_GT(coc_angle_rad(old, 0.3, accommodate(old, 0.3)), 3.5e-3 * (1 / 0.3 - 0.5) - 1e-12);
  // Hyperopia +2 D: accommodation spent on distance; with presbyopia, even infinity is blurred
  const EyeParams hyperope = parse_eye_preset("hyperopia:+2");
  EXPECT_NEAR(accommodate(hyperope, INFINITY), 0.0, 1e-15);
  const EyeParams both = parse_eye_preset("presbyopia:60+hyperopia:2");
  EXPECT_NEAR(accommodate(both, INFINITY), -1.5, 1e-12);
  EXPECT_NEAR(coc_angle_rad(both, INFINITY, accommodate(both, INFINITY)), 3.5e-3 * 1.5, 1e-12);
}

TEST(Eye, PresetsAndErrors) {
  EXPECT_DOUBLE_EQ(parse_eye_preset("glaucoma").glaucoma, 0.5);
  EXPECT_DOUBLE_EQ(parse_eye_preset("glaucoma:0.8").glaucoma, 0.8);
  EXPECT_GT(peripheral_penalty_per_deg(parse_eye_preset("glaucoma:1")), peripheral_penalty_per_deg(parse_eye_preset("healthy")));
  EXPECT_DOUBLE_EQ(parse_eye_preset("myopia:3").refraction_d, -3);
  const EyeParams a = parse_eye_preset("astigmatism:1.5@90");
  EXPECT_DOUBLE_EQ(a.cylinder_d, 1.5);
  EXPECT_DOUBLE_EQ(a.cylinder_axis_deg, 90);
  for (const char* bad : {"", "blind", "glaucoma:2", "myopia:x", "presbyopia:200", "hyperopia"})
    EXPECT_THROW(parse_eye_preset(bad), Error) << bad;
}
