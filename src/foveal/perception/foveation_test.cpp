// Tests of the display geometry, eccentricity and acuity model against DESIGN.md's formulas.
#include "foveal/perception/foveation.h"
#include "foveal/util/error.h"

#include <gtest/gtest.h>

#include <cmath>
#include <numbers>

using namespace foveal;

TEST(Display, PaperLabDisplayGeometry) {
  const Display d;  // 47.5 × 30 cm, 60 cm, 1680 × 1050
  EXPECT_NEAR(field_of_view_x_deg(d), 2 * std::atan(23.75 / 60) * kDeg, 1e-12);
  EXPECT_NEAR(field_of_view_x_deg(d), 43.2, 0.1);  // the paper: 43°
  EXPECT_NEAR(field_of_view_y_deg(d), 28.1, 0.1);  // the paper: 28°
  EXPECT_NEAR(pixels_per_degree(d), 38.9, 0.1);    // the paper: ≈ 40
  EXPECT_NEAR(max_display_cpd(d), pixels_per_degree(d) / 2, 1e-12);
}

TEST(Display, ParseAndReject) {
  const Display d = parse_display("50,30,70,1920,1080");
  EXPECT_EQ(d.res_x, 1920);
  EXPECT_DOUBLE_EQ(d.distance_cm, 70);
  Display keep;
  keep.res_x = 840;
  keep.res_y = 525;
  EXPECT_EQ(parse_display("50,30,70", keep).res_x, 840);
  EXPECT_THROW(parse_display("0,30,60"), Error);
  EXPECT_THROW(parse_display("47.5,30,-1"), Error);
  EXPECT_THROW(parse_display("47.5,30"), Error);
  EXPECT_THROW(parse_display("47.5,abc,60"), Error);
  EXPECT_THROW(parse_display("47.5,30,60,0,1050"), Error);
}

TEST(Acuity, Equation4AtKnownPoints) {
  // Without the display limit: 43.1 at the fovea, half of it at E2 = 3.118°
  EXPECT_DOUBLE_EQ(acuity_cutoff_cpd(0.0, 1000.0), 43.1);
  EXPECT_NEAR(acuity_cutoff_cpd(3.118, 1000.0), 21.55, 1e-12);
  EXPECT_NEAR(acuity_cutoff_cpd(10.0, 1000.0), 43.1 * 3.118 / 13.118, 1e-12);
  // The display caps it
  EXPECT_DOUBLE_EQ(acuity_cutoff_cpd(0.0, 19.4), 19.4);
  EXPECT_DOUBLE_EQ(acuity_cutoff_cpd(2.0, 19.4), 19.4);
}

TEST(Budget, RaysAndBlendFollowTheFormulas) {
  FoveationParams p;                                // n_max 400, n_min 0, γ 2, β 0
  EXPECT_DOUBLE_EQ(blend_weight(0.3, 10, p), 1.0);  // the default: AO wherever rays are cast
  p.beta = 1;
  EXPECT_EQ(ao_ray_budget(1.0, p), 400);
  EXPECT_EQ(ao_ray_budget(0.5, p), 100);
  EXPECT_EQ(ao_ray_budget(0.0, p), 0);
  p.min_rays = 8;
  p.gamma = 1;
  EXPECT_EQ(ao_ray_budget(0.5, p), 8 + 196);
  EXPECT_DOUBLE_EQ(blend_weight(0.3, 10, p), 0.3);
  EXPECT_DOUBLE_EQ(blend_weight(0.3, 0, p), 0.0);  // no rays, no AO
  p.beta = 2;
  EXPECT_DOUBLE_EQ(blend_weight(0.5, 10, p), 0.25);
}

TEST(Eccentricity, ExactAngleBetweenEyeRays) {
  const Display d;
  const FoveationParams circle{1.0};
  const FoveationModel m(d, 1680, 1050, {840, 525}, circle);
  // Screen-centre gaze, right edge of the screen: atan(W/2 / d)
  const FoveaSample edge = m.evaluate_at(1680, 525);
  EXPECT_NEAR(edge.angle_deg, std::atan(23.75 / 60) * kDeg, 1e-9);
  EXPECT_NEAR(edge.effective_deg, edge.angle_deg, 1e-9);
  // Exact, not linear in pixels: the outer half of the half-width spans less angle than the inner half
  const double inner = m.evaluate_at(840 + 420, 525).angle_deg;
  EXPECT_GT(inner, edge.angle_deg - inner);
  // Off-centre gaze: angle between the two eye rays
  const FoveationModel off(d, 1680, 1050, {0, 0}, circle);
  const glm::dvec3 a = glm::normalize(off.eye_ray(0, 0)), b = glm::normalize(off.eye_ray(1680, 1050));
  EXPECT_NEAR(off.evaluate_at(1680, 1050).angle_deg, std::acos(glm::dot(a, b)) * kDeg, 1e-6);
}

TEST(Eccentricity, EllipseWidensTheRegionHorizontally) {
  const Display d{48.0, 30.0, 60.0, 1680, 1050};  // square pixels
  const FoveationModel m(d, 1680, 1050, {840, 525}, FoveationParams{});
  const FoveaSample right = m.evaluate_at(840 + 300, 525), down = m.evaluate_at(840, 525 + 300);
  EXPECT_NEAR(right.angle_deg, down.angle_deg, 1e-9);  // square pixels: same angle
  EXPECT_NEAR(right.effective_deg, right.angle_deg / 1.538, 1e-9);
  EXPECT_NEAR(down.effective_deg, down.angle_deg, 1e-9);
  EXPECT_GT(right.quality, down.quality);
}

TEST(Foveation, QualityIsOneInTheFoveaAndFallsMonotonically) {
  const Display d;
  for (glm::dvec2 gaze : {glm::dvec2(420, 262), glm::dvec2(0, 0), glm::dvec2(-300, 900)}) {
    const FoveationModel m(d, 840, 525, gaze, FoveationParams{});
    // At the gaze (if on screen) q = 1 exactly, n = n_max, b = 1
    const FoveaSample at = m.evaluate_at(gaze.x, gaze.y);
    EXPECT_EQ(at.quality, 1.0);
    EXPECT_EQ(at.rays, 400);
    EXPECT_EQ(at.blend, 1.0);
    // Along rays away from the gaze: q, n, b never increase
    for (double angle = 0; angle < 6.28; angle += 0.7) {
      FoveaSample prev = at;
      for (double r = 1; r < 2000; r += 7) {
        const FoveaSample s = m.evaluate_at(gaze.x + r * std::cos(angle), gaze.y + r * std::sin(angle));
        EXPECT_LE(s.quality, prev.quality + 1e-12);
        EXPECT_LE(s.rays, prev.rays);
        EXPECT_LE(s.blend, prev.blend + 1e-12);
        prev = s;
      }
    }
  }
}

TEST(Foveation, SymmetricAboutACentredGaze) {
  const FoveationModel m(Display{}, 840, 525, {420, 262.5}, FoveationParams{});
  for (int y = 0; y < 525; y += 37)
    for (int x = 0; x < 420; x += 29) {
      const FoveaSample a = m.evaluate(x, y), b = m.evaluate(839 - x, y), c = m.evaluate(x, 524 - y);
      EXPECT_NEAR(a.quality, b.quality, 1e-12);
      EXPECT_NEAR(a.quality, c.quality, 1e-12);
      EXPECT_EQ(a.rays, b.rays);
    }
}

TEST(Foveation, FoveaRadiusMatchesTheDisplayLimit) {
  // q = 1 exactly while 43.1·E2/(E2+E) ≥ max_cpd, i.e. E ≤ E2·(43.1/max_cpd − 1)
  const Display d;
  const double limit = kAcuityE2Deg * (kAcuityFovealCpd / max_display_cpd(d) - 1.0);
  const FoveationModel m(d, 1680, 1050, {840, 525}, FoveationParams{1.0});
  // Pixel offset below the centre at a given angle: d·tan(angle) in cm, over the pixel height
  auto below = [&](double deg) { return 525 + d.distance_cm * std::tan(deg / kDeg) / (d.height_cm / d.res_y); };
  EXPECT_EQ(m.evaluate_at(840, below(limit - 0.01)).quality, 1.0);
  EXPECT_LT(m.evaluate_at(840, below(limit + 0.01)).quality, 1.0);
  EXPECT_NEAR(m.evaluate_at(840, below(limit + 1.0)).effective_deg, limit + 1.0, 1e-9);
}

TEST(Foveation, TheSinglePrecisionModelAgreesWithTheDoubleOne) {
  // Abramowitz & Stegun 4.4.47 (|error| ≤ 1e-5 rad) against atan2, on both sides of 45°
  for (int k = 0; k <= 1000; ++k) {
    const float angle = 1.5707f * static_cast<float>(k) / 1000;
    EXPECT_NEAR(fast_atan2_positive(std::sin(angle), std::cos(angle)), angle, 1.2e-5f) << angle;
  }
  // The model over a 1680×1050 display with the gaze off-centre: E within 2e-3°, q within 1e-4
  const Display d;
  const FoveationModel m(d, 840, 525, {600, 150}, FoveationParams{});
  size_t budgets_equal = 0, pixels = 0;
  for (int y = 0; y < 525; y += 3)
    for (int x = 0; x < 840; x += 3) {
      const glm::dvec3 p = glm::normalize(m.eye_ray(x + 0.5, y + 0.5));
      const FoveaSample exact = m.evaluate_direction(p), fast = m.evaluate_direction_fast(glm::vec3(p));
      EXPECT_NEAR(fast.effective_deg, exact.effective_deg, 2e-3);
      EXPECT_NEAR(fast.quality, exact.quality, 1e-4);
      EXPECT_LE(std::abs(fast.rays - exact.rays), 1);
      budgets_equal += fast.rays == exact.rays ? 1 : 0;
      ++pixels;
    }
  EXPECT_GT(budgets_equal, pixels * 99 / 100);
}
