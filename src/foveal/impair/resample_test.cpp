// The GPU's per-pixel resampling (impair/resample.h) against OpenCV's own operations on the CPU.
#include "foveal/impair/resample.h"

#include <gtest/gtest.h>
#include <opencv2/core.hpp>
#include <opencv2/imgproc.hpp>

#include <cmath>
#include <functional>
#include <random>

namespace foveal {
namespace {

cv::Mat random_image(int w, int h, int cn, uint32_t seed) {
  cv::Mat m(h, w, CV_MAKETYPE(CV_32F, cn));
  std::mt19937 rng(seed);
  std::uniform_real_distribution<float> u(0.0f, 2.0f);
  for (int y = 0; y < h; ++y)
    for (int x = 0; x < w * cn; ++x) m.ptr<float>(y)[x] = u(rng);
  return m;
}

// The largest difference between OpenCV's image and the body's, over every pixel and channel, and
// where it was (the bodies differ from OpenCV only in the order of float additions: ~1e-6 here).
struct Worst {
  double diff = 0;
  int x = -1, y = -1;
};
Worst compare(const cv::Mat& expected, const std::function<float(int, int, int)>& body) {
  Worst w;
  const int cn = expected.channels();
  for (int y = 0; y < expected.rows; ++y)
    for (int x = 0; x < expected.cols; ++x)
      for (int c = 0; c < cn; ++c) {
        const double d = std::abs(double(expected.ptr<float>(y)[x * cn + c]) - body(x, y, c));
        if (!(d <= w.diff)) w = {d, x, y};
      }
  return w;
}

constexpr double kTolerance = 2e-6;  // values in [0, 2]: a few float roundings

TEST(Resample, PyrDownIsOpenCvs) {
  for (auto [w, h, cn] : {std::tuple{64, 48, 3}, {65, 47, 3}, {33, 18, 1}, {17, 16, 1}, {160, 90, 3}}) {
    const cv::Mat src = random_image(w, h, cn, w * 7 + h);
    cv::Mat dst;
    cv::pyrDown(src, dst);
    ASSERT_EQ(dst.cols, (w + 1) / 2);
    const Worst e = compare(dst, [&](int x, int y, int c) { return resample::pyr_down_at(src.ptr<float>(), w, h, cn, x, y, c); });
    EXPECT_LE(e.diff, kTolerance) << w << "x" << h << "x" << cn << " at " << e.x << "," << e.y;
  }
}

TEST(Resample, PyrUpIsOpenCvsAtEvenAndOddSizes) {
  for (auto [w, h, cn] : {std::tuple{32, 24, 3}, {33, 24, 3}, {32, 23, 1}, {9, 8, 1}, {80, 45, 3}}) {
    const cv::Mat src = random_image(w, h, cn, w * 3 + h);
    for (auto [dw, dh] : {std::pair{2 * w, 2 * h}, {2 * w - 1, 2 * h}, {2 * w, 2 * h - 1}, {2 * w - 1, 2 * h - 1}}) {
      cv::Mat dst;
      cv::pyrUp(src, dst, cv::Size(dw, dh));
      const Worst e = compare(dst, [&](int x, int y, int c) { return resample::pyr_up_at(src.ptr<float>(), w, h, cn, x, y, c); });
      EXPECT_LE(e.diff, kTolerance) << w << "x" << h << " → " << dw << "x" << dh << " at " << e.x << "," << e.y;
    }
  }
}

TEST(Resample, LinearResizeIsOpenCvsDownUpAndByHalves) {
  struct Case {
    int sw, sh, cn, dw, dh;
  };
  for (const Case k : {Case{160, 90, 3, 1280, 720}, Case{147, 110, 3, 1024, 768}, Case{140, 88, 1, 840, 525}, Case{1280, 720, 1, 640, 360},
                       Case{1280, 720, 1, 320, 180}, Case{841, 525, 1, 421, 263}, Case{841, 525, 1, 106, 66}, Case{37, 29, 3, 37, 29}}) {
    const cv::Mat src = random_image(k.sw, k.sh, k.cn, k.sw + k.dh);
    cv::Mat dst;
    cv::resize(src, dst, cv::Size(k.dw, k.dh), 0, 0, cv::INTER_LINEAR);
    const Worst e = compare(
        dst, [&](int x, int y, int c) { return resample::resize_linear_at(src.ptr<float>(), k.sw, k.sh, k.cn, k.dw, k.dh, x, y, c); });
    EXPECT_LE(e.diff, kTolerance) << k.sw << "x" << k.sh << " → " << k.dw << "x" << k.dh << " at " << e.x << "," << e.y;
  }
}

TEST(Resample, AreaResizeIsOpenCvsForWholeAndFractionalFactors) {
  struct Case {
    int sw, sh, dw, dh;
  };
  for (const Case k :
       {Case{1280, 720, 160, 90}, Case{840, 525, 140, 88}, Case{1024, 768, 147, 110}, Case{420, 262, 140, 88}, Case{100, 60, 100, 60}}) {
    const cv::Mat src = random_image(k.sw, k.sh, 3, k.sw + k.sh);
    cv::Mat dst;
    cv::resize(src, dst, cv::Size(k.dw, k.dh), 0, 0, cv::INTER_AREA);
    const Worst e =
        compare(dst, [&](int x, int y, int c) { return resample::resize_area_at(src.ptr<float>(), k.sw, k.sh, 3, k.dw, k.dh, x, y, c); });
    EXPECT_LE(e.diff, kTolerance) << k.sw << "x" << k.sh << " → " << k.dw << "x" << k.dh << " at " << e.x << "," << e.y;
  }
}

TEST(Resample, RemapIsOpenCvsWithReflectedBorders) {
  const int w = 61, h = 40;
  const cv::Mat src = random_image(w, h, 3, 5);
  cv::Mat mx(h, w, CV_32F), my(h, w, CV_32F);
  std::mt19937 rng(9);
  std::uniform_real_distribution<float> d(-6.0f, 6.0f);
  for (int y = 0; y < h; ++y)
    for (int x = 0; x < w; ++x) {
      mx.at<float>(y, x) = x + d(rng);  // some past every edge
      my.at<float>(y, x) = y + d(rng);
    }
  mx.at<float>(0, 0) = 3.015625f;  // exactly half a 1/32 step: rounded to even
  cv::Mat dst;
  cv::remap(src, dst, mx, my, cv::INTER_LINEAR, cv::BORDER_REFLECT);
  const Worst e = compare(dst, [&](int x, int y, int c) {
    return resample::remap_linear_at(src.ptr<float>(), w, h, 3, mx.at<float>(y, x), my.at<float>(y, x), c);
  });
  EXPECT_LE(e.diff, kTolerance) << "at " << e.x << "," << e.y;
}

TEST(Resample, BordersReflectAsOpenCvSays) {
  for (int n : {1, 2, 5}) {
    for (int p = -2 * n; p < 3 * n; ++p) {
      EXPECT_EQ(resample::reflect101(p, n), cv::borderInterpolate(p, n, cv::BORDER_REFLECT_101)) << p << " in " << n;
      EXPECT_EQ(resample::reflect(p, n), cv::borderInterpolate(p, n, cv::BORDER_REFLECT)) << p << " in " << n;
    }
  }
}

}  // namespace
}  // namespace foveal
