// Tests of the display geometry, eccentricity and acuity model against DESIGN.md's formulas.
#include "foveal/perception/foveation.h"
#include "foveal/util/error.h"

#include <gtest/gtest.h>

#include <cmath>
#include <numbers>
#include <vector>

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
  // The model says how far its fovea reaches (3.8° here); a display that resolves 43.1 cycles/degree has none
  EXPECT_DOUBLE_EQ(m.fovea_reach_deg(), limit);
  EXPECT_NEAR(limit, 3.79, 0.01);
  Display sharp;
  sharp.res_x = 1680 * 5;
  sharp.res_y = 1050 * 5;
  const FoveationModel fine(sharp, sharp.res_x, sharp.res_y, {sharp.res_x / 2.0, sharp.res_y / 2.0}, FoveationParams{1.0});
  EXPECT_EQ(fine.fovea_reach_deg(), 0.0);
  EXPECT_LT(fine.evaluate_at(sharp.res_x / 2.0, sharp.res_y / 2.0 + 5).quality, 1.0);
}

TEST(Foveation, TheSinglePrecisionModelAgreesWithTheDoubleOne) {
  // Abramowitz & Stegun 4.4.47 (|error| ≤ 1e-5 rad) against atan2, on both sides of 45°
  for (int k = 0; k <= 1000; ++k) {
    const float angle = 1.5707f * static_cast<float>(k) / 1000;
    EXPECT_NEAR(fast_atan2_positive(std::sin(angle), std::cos(angle)), angle, 1.2e-5f) << angle;
  }
  // The model over a 1680×1050 display with the gaze off-centre: E within 2e-3°, q within 1e-4;
  // the defaults (γ = 2, β = 0: their own loops) and another γ and β (the general ones)
  const Display d;
  FoveationParams other;
  other.gamma = 1.5;
  other.beta = 1.0;
  other.min_rays = 2;
  for (const FoveationParams& params : {FoveationParams{}, other}) {
    const FoveationModel m(d, 840, 525, {600, 150}, params);
    std::vector<float> x, y, z;
    std::vector<FoveaSample> exact;
    for (int py = 0; py < 525; py += 3)
      for (int px = 0; px < 840; px += 3) {
        const glm::dvec3 p = glm::normalize(m.eye_ray(px + 0.5, py + 0.5));
        x.push_back(static_cast<float>(p.x));
        y.push_back(static_cast<float>(p.y));
        z.push_back(static_cast<float>(p.z));
        exact.push_back(m.evaluate_direction(p));
      }
    // The gaze's own pixel too (no direction away from it: E = 0)
    const glm::dvec3 at = glm::normalize(m.eye_ray(600, 150));
    x.push_back(static_cast<float>(at.x));
    y.push_back(static_cast<float>(at.y));
    z.push_back(static_cast<float>(at.z));
    exact.push_back(m.evaluate_direction(at));
    const size_t n = x.size();
    std::vector<float> e(n), q(n), b(n);
    std::vector<uint16_t> r(n);
    m.evaluate_directions_fast(x.data(), y.data(), z.data(), n, e.data(), q.data(), r.data(), b.data());
    size_t budgets_equal = 0;
    for (size_t i = 0; i < n; ++i) {
      EXPECT_NEAR(e[i], exact[i].effective_deg, 2e-3) << i;
      EXPECT_NEAR(q[i], exact[i].quality, 1e-4) << i;
      EXPECT_LE(std::abs(static_cast<int>(r[i]) - exact[i].rays), 1) << i;
      EXPECT_NEAR(b[i], exact[i].blend, 2e-4) << i;
      budgets_equal += r[i] == exact[i].rays ? 1 : 0;
    }
    EXPECT_GT(budgets_equal, n * 99 / 100);
    EXPECT_NEAR(e.back(), 0.0, 2e-3);
    EXPECT_EQ(q.back(), 1.0f);
    EXPECT_EQ(r.back(), params.max_rays);
    // Without `blend` the rest is the same
    std::vector<float> e2(n), q2(n);
    std::vector<uint16_t> r2(n);
    m.evaluate_directions_fast(x.data(), y.data(), z.data(), n, e2.data(), q2.data(), r2.data(), nullptr);
    EXPECT_EQ(e2, e);
    EXPECT_EQ(r2, r);
  }
}
