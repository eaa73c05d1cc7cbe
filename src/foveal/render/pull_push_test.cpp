// Pull-push: known pixels kept, unknown ones a convex blend of the known ones nearest them.
#include "foveal/render/pull_push.h"

#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <random>

namespace {

using foveal::PullPush;

// As the loop uses it: a known pixel's own value, else the estimate (`fallback` where nothing is known)
void fill(PullPush& p, int width, int height, const float* value, const uint8_t* known, float fallback, float* out) {
  p.pull(width, height, [&](size_t i) { return std::pair{known[i] != 0, value[i]}; });
  const bool any = p.push();
  for (size_t i = 0; i < static_cast<size_t>(width) * static_cast<size_t>(height); ++i)
    out[i] = known[i] ? value[i] : any ? p.estimate(i) : fallback;
}

struct Field {
  int width, height;
  std::vector<float> value, out;
  std::vector<uint8_t> known;
  Field(int w, int h) : width(w), height(h), value(static_cast<size_t>(w) * h), out(value.size()), known(value.size()) {}
  size_t at(int x, int y) const { return static_cast<size_t>(y) * width + x; }
};

TEST(PullPush, AConstantFieldIsFilledWithItsValueAndKnownPixelsAreKept) {
  Field f(97, 61);  // odd sizes: the levels round up
  std::mt19937 rng(3);
  for (size_t i = 0; i < f.value.size(); ++i) {
    f.known[i] = rng() % 10 == 0;
    f.value[i] = f.known[i] ? 0.625f : -1.0f;
  }
  PullPush pp;
  fill(pp, f.width, f.height, f.value.data(), f.known.data(), 7.0f, f.out.data());
  for (size_t i = 0; i < f.value.size(); ++i) EXPECT_NEAR(f.out[i], 0.625f, 1e-5) << i;
}

// A single pixel, a single row or column: the levels round up to one cell, and one known pixel
// fills them all
TEST(PullPush, OnePixelAndOneRowOrColumnAreFilled) {
  for (const auto& [w, h] : {std::pair{1, 1}, std::pair{7, 1}, std::pair{1, 9}, std::pair{2, 3}}) {
    Field f(w, h);
    f.known.back() = 1;
    f.value.back() = 0.25f;
    PullPush pp;
    fill(pp, f.width, f.height, f.value.data(), f.known.data(), 9.0f, f.out.data());
    for (float v : f.out) EXPECT_NEAR(v, 0.25f, 1e-6) << w << "x" << h;
  }
}

TEST(PullPush, NothingKnownIsTheFallback) {
  Field f(40, 30);
  PullPush pp;
  fill(pp, f.width, f.height, f.value.data(), f.known.data(), 0.3f, f.out.data());
  for (float v : f.out) EXPECT_EQ(v, 0.3f);
}

// Every estimate is a weighted mean of known values (area means and bilinear weights are
// non-negative and sum to one, and each level blends in proportion to coverage): within their range
TEST(PullPush, EveryEstimateLiesWithinTheKnownValuesRange) {
  Field f(200, 120);
  std::mt19937 rng(11);
  std::uniform_real_distribution<float> u(0.2f, 0.9f);
  for (size_t i = 0; i < f.value.size(); ++i) {
    f.known[i] = rng() % 50 == 0;
    f.value[i] = u(rng);
  }
  float lo = 1, hi = 0;
  for (size_t i = 0; i < f.value.size(); ++i)
    if (f.known[i]) lo = std::min(lo, f.value[i]), hi = std::max(hi, f.value[i]);
  PullPush p;
  fill(p, f.width, f.height, f.value.data(), f.known.data(), 5.0f, f.out.data());
  for (size_t i = 0; i < f.value.size(); ++i) {
    if (f.known[i]) EXPECT_EQ(f.out[i], f.value[i]) << i;
    EXPECT_GE(f.out[i], lo - 1e-5f) << i;
    EXPECT_LE(f.out[i], hi + 1e-5f) << i;
  }
  // The same again with the pyramid kept: the same result
  std::vector<float> again(f.out.size());
  fill(p, f.width, f.height, f.value.data(), f.known.data(), 5.0f, again.data());
  EXPECT_EQ(again, f.out);
}

// Pulled a few rows a step, in any order (the real-time loop builds a view over frames), the
// estimate is the whole pull's, to the bit
TEST(PullPush, PullingInRowsIsTheWholePull) {
  Field f(203, 121);  // (odd sizes: the first level's last row and column from one row or column of pixels)
  std::mt19937 rng(5);
  std::uniform_real_distribution<float> u(0.0f, 1.0f);
  for (size_t i = 0; i < f.value.size(); ++i) {
    f.known[i] = rng() % 7 == 0;
    f.value[i] = u(rng);
  }
  auto at = [&](size_t i) { return std::pair{f.known[i] != 0, f.value[i]}; };
  PullPush whole, rows;
  whole.pull(f.width, f.height, at);
  ASSERT_TRUE(whole.push());
  rows.prepare(f.width, f.height);
  const int n = PullPush::first_rows(f.height);
  ASSERT_EQ(n, 61);
  // the rows in steps of 1 to 7, the later half first
  for (int y = n / 2; y < n;) {
    const int e = std::min(n, y + 1 + static_cast<int>(rng() % 7));
    rows.pull_rows(f.width, f.height, at, y, e);
    y = e;
  }
  for (int y = 0; y < n / 2;) {
    const int e = std::min(n / 2, y + 1 + static_cast<int>(rng() % 7));
    rows.pull_rows(f.width, f.height, at, y, e);
    y = e;
  }
  rows.pull_levels();
  ASSERT_TRUE(rows.push());
  for (size_t i = 0; i < f.value.size(); ++i) ASSERT_EQ(rows.estimate(i), whole.estimate(i)) << i;
  // A row left out changes the estimate
  PullPush missing;
  missing.prepare(f.width, f.height);
  missing.pull_rows(f.width, f.height, at, 0, n - 1);
  missing.pull_levels();
  missing.push();
  size_t differ = 0;
  for (size_t i = 0; i < f.value.size(); ++i) differ += missing.estimate(i) != whole.estimate(i) ? 1 : 0;
  EXPECT_GT(differ, 0u);
}

// The known region's values carry on past its edge, where a constant would jump: a disc known to be
// 0.4 on the left half of the image and 0.8 on the right leaves, just outside each half's edge,
// nearly that half's value, and a smooth passage between them
TEST(PullPush, AnUnknownPixelTakesTheValueOfTheKnownPixelsNearestIt) {
  Field f(256, 128);
  for (int y = 0; y < f.height; ++y)
    for (int x = 0; x < f.width; ++x) {
      const bool inside = std::hypot(x - 128.0, y - 64.0) < 48;
      f.known[f.at(x, y)] = inside;
      f.value[f.at(x, y)] = x < 128 ? 0.4f : 0.8f;
    }
  PullPush pp;
  fill(pp, f.width, f.height, f.value.data(), f.known.data(), 0.0f, f.out.data());
  EXPECT_NEAR(f.out[f.at(128 - 52, 64)], 0.4f, 0.05f);  // 4 px outside the disc, on the left
  EXPECT_NEAR(f.out[f.at(128 + 52, 64)], 0.8f, 0.05f);  // and on the right
  EXPECT_LT(f.out[f.at(4, 64)], 0.6f);                  // far out, still nearer the left's value than the right's
  EXPECT_GT(f.out[f.at(251, 64)], 0.6f);
  // Along the row through the centre, outside the disc, neighbouring pixels differ little: no edge
  for (int x = 1; x < f.width; ++x) {
    if (std::abs(x - 128) < 49) continue;
    EXPECT_LT(std::abs(f.out[f.at(x, 64)] - f.out[f.at(x - 1, 64)]), 0.03f) << x;
  }
}

}  // namespace
