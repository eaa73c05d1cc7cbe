// Tests of the scrambled Sobol sequence and the cosine-weighted hemisphere mapping.
#include "foveal/util/sampling.h"

#include <gtest/gtest.h>

#include <cmath>
#include <numbers>
#include <set>

using namespace foveal;

TEST(Sampling, SobolPrefixesAreStratified) {
  // (0,2)-sequence: every power-of-two prefix puts one point in each elementary interval,
  // also after the per-pixel XOR scrambling
  for (uint32_t pixel : {0U, 12345U, 0xdeadbeefU}) {
    for (int log_n = 2; log_n <= 8; log_n += 2) {
      const uint32_t n = 1U << log_n, side = 1U << (log_n / 2);
      std::set<uint32_t> cells;
      for (uint32_t k = 0; k < n; ++k) {
        const glm::vec2 u = scrambled_sobol_2d(k, pixel);
        ASSERT_GE(u.x, 0.0f);
        ASSERT_LT(u.x, 1.0f);
        ASSERT_GE(u.y, 0.0f);
        ASSERT_LT(u.y, 1.0f);
        cells.insert(static_cast<uint32_t>(u.x * side) * side + static_cast<uint32_t>(u.y * side));
      }
      EXPECT_EQ(cells.size(), n) << "pixel " << pixel << ", n " << n;
    }
  }
}

TEST(Sampling, PixelsGetDifferentScrambles) {
  EXPECT_NE(scrambled_sobol_2d(0, pixel_seed(1, 10, 10)), scrambled_sobol_2d(0, pixel_seed(1, 11, 10)));
  EXPECT_NE(scrambled_sobol_2d(0, pixel_seed(1, 10, 10)), scrambled_sobol_2d(0, pixel_seed(2, 10, 10)));
  EXPECT_EQ(scrambled_sobol_2d(7, pixel_seed(3, 5, 9)), scrambled_sobol_2d(7, pixel_seed(3, 5, 9)));
}

TEST(Sampling, CosineHemisphereHasTheRightMoments) {
  // Unit directions above the surface; E[cos θ] = 2/3 under the cosine density
  double sum = 0;
  const int n = 1 << 14;
  for (int k = 0; k < n; ++k) {
    const glm::vec3 d = cosine_hemisphere(scrambled_sobol_2d(k, 99));
    ASSERT_NEAR(glm::length(d), 1.0f, 1e-5f);
    ASSERT_GE(d.z, 0.0f);
    sum += d.z;
  }
  EXPECT_NEAR(sum / n, 2.0 / 3.0, 1e-3);
}

TEST(Sampling, FrameIsOrthonormal) {
  for (glm::vec3 n : {glm::vec3(0, 0, 1), glm::vec3(0, 0, -1), glm::normalize(glm::vec3(1, 2, -3)), glm::vec3(1, 0, 0)}) {
    const Frame3 f = make_frame(n);
    EXPECT_NEAR(glm::dot(f.t, f.b), 0.0f, 1e-6f);
    EXPECT_NEAR(glm::dot(f.t, n), 0.0f, 1e-6f);
    EXPECT_NEAR(glm::dot(f.b, n), 0.0f, 1e-6f);
    EXPECT_NEAR(glm::length(f.t), 1.0f, 1e-6f);
    EXPECT_NEAR(glm::dot(f.to_world({0, 0, 1}), n), 1.0f, 1e-6f);
  }
}

TEST(Sampling, FastCosSinMatchesLibm) {
  for (int i = 0; i < 100000; ++i) {
    const float t = i / 100000.0f;
    const glm::vec2 cs = cos_sin_2pi(t);
    ASSERT_NEAR(cs.x, std::cos(2.0 * std::numbers::pi * t), 4e-6) << t;
    ASSERT_NEAR(cs.y, std::sin(2.0 * std::numbers::pi * t), 4e-6) << t;
  }
}

TEST(Sampling, AngleAtan2MatchesLibm) {
  double worst = 0;
  for (int k = 0; k <= 100000; ++k) {
    const double theta = std::numbers::pi * k / 100000.0;
    for (double length : {1.0, 0.37, 12.5}) {
      const float y = static_cast<float>(length * std::sin(theta)), x = static_cast<float>(length * std::cos(theta));
      worst = std::max(worst, std::abs(double(angle_atan2(y, x)) - std::atan2(double(y), double(x))));
    }
  }
  EXPECT_LT(worst, 1.3e-5);
  EXPECT_EQ(angle_atan2(0.0f, 0.0f), 0.0f);
  EXPECT_NEAR(angle_atan2(0.0f, -1.0f), std::numbers::pi, 1e-6);
}
