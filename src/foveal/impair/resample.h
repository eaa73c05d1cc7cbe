// foveal/impair/resample.h — one output pixel of OpenCV's pyrDown, pyrUp, resize (INTER_LINEAR,
// INTER_AREA) and remap (INTER_LINEAR, BORDER_REFLECT) on float images, for the CUDA backend.
//
// The impairments (impairments.cpp) run these operations through OpenCV on the CPU; the GPU has no
// OpenCV, so its kernels compute each output pixel with the functions below, written to OpenCV's
// own definitions (imgproc's pyramids.cpp, resize.cpp, imgwarp.cpp, 4.x): the same taps, borders,
// weights and rounding of coordinates, so that both devices give the same image up to the order of
// float additions. A test holds every function to OpenCV's result on the CPU, over odd and even
// sizes. Images are row-major with `cn` interleaved channels.
#pragma once

#include "foveal/util/hd.h"

#include <cmath>

namespace foveal::resample {

// cv::borderInterpolate with BORDER_REFLECT_101 (…, 2, 1 | 0, 1, 2, … n−1 | n−2, …), n > 1.
FOVEAL_HD inline int reflect101(int p, int n) {
  if (n == 1) return 0;
  while (p < 0 || p >= n) p = p < 0 ? -p : 2 * n - 2 - p;
  return p;
}
// … with BORDER_REFLECT (…, 1, 0 | 0, 1, … n−1 | n−1, n−2, …).
FOVEAL_HD inline int reflect(int p, int n) {
  if (n == 1) return 0;
  while (p < 0 || p >= n) p = p < 0 ? -p - 1 : 2 * n - 1 - p;
  return p;
}

// cv::pyrDown: the 5 × 5 binomial kernel [1 4 6 4 1]²/256 at source (2x, 2y), BORDER_REFLECT_101;
// the output is ((w + 1)/2) × ((h + 1)/2).
FOVEAL_HD inline float pyr_down_at(const float* s, int sw, int sh, int cn, int x, int y, int c) {
  int xs[5], ys[5];
  for (int k = 0; k < 5; ++k) xs[k] = reflect101(2 * x + k - 2, sw) * cn + c, ys[k] = reflect101(2 * y + k - 2, sh);
  float r[5];
  for (int k = 0; k < 5; ++k) {
    const float* row = s + static_cast<size_t>(ys[k]) * sw * cn;
    r[k] = row[xs[0]] + row[xs[4]] + (row[xs[1]] + row[xs[3]]) * 4.0f + row[xs[2]] * 6.0f;
  }
  return (r[0] + r[4] + (r[1] + r[3]) * 4.0f + r[2] * 6.0f) * (1.0f / 256.0f);
}

// cv::pyrUp to any size of (2w or 2w − 1) × (2h or 2h − 1): the source upsampled with the kernel
// [1 4 6 4 1]/8 in each direction; beyond the first row and column the source reflects (row −1 is
// row 1), beyond the last it repeats (OpenCV's own border for this operation).
namespace detail {
// The horizontal pass at output column x of source row `row` (OpenCV's forms at the edges).
FOVEAL_HD inline float pyr_up_row(const float* row, int sw, int cn, int x, int c) {
  const int sx = x >> 1;
  const float a = row[sx * cn + c];
  if (sw == 1) return a * 8.0f;
  if (x & 1) return sx + 1 < sw ? (a + row[(sx + 1) * cn + c]) * 4.0f : a * 8.0f;
  if (sx == 0) return a * 6.0f + row[cn + c] * 2.0f;
  if (sx == sw - 1) return row[(sx - 1) * cn + c] + a * 7.0f;
  return row[(sx - 1) * cn + c] + a * 6.0f + row[(sx + 1) * cn + c];
}
}  // namespace detail

FOVEAL_HD inline float pyr_up_at(const float* s, int sw, int sh, int cn, int x, int y, int c) {
  const int sy = y >> 1;
  // rows sy − 1, sy, sy + 1 as OpenCV takes them: borderInterpolate(2·r, 2·h, REFLECT_101) / 2
  auto row_at = [&](int r) {
    const int rr = reflect101(2 * r, 2 * sh) / 2;
    return detail::pyr_up_row(s + static_cast<size_t>(rr) * sw * cn, sw, cn, x, c);
  };
  const float r1 = row_at(sy), r2 = row_at(sy + 1);
  if (y & 1) return (r1 + r2) * 4.0f * (1.0f / 64.0f);
  return (row_at(sy - 1) + r1 * 6.0f + r2) * (1.0f / 64.0f);
}

// cv::resize with INTER_AREA, one output pixel: each source pixel weighted by its overlap with
// the output pixel's footprint (OpenCV's computeResizeAreaTab); integer factors are plain box means.
namespace detail {
// Calls tap(source index, weight) for each source pixel under output pixel d, in order.
template <class Tap>
FOVEAL_HD inline void area_taps(int ssize, int dsize, int d, Tap&& tap) {
  const double scale = static_cast<double>(ssize) / dsize;
  const double f1 = d * scale, f2 = f1 + scale;
  const double cell = scale < ssize - f1 ? scale : ssize - f1;
  int s2 = static_cast<int>(floor(f2));
  s2 = s2 < ssize - 1 ? s2 : ssize - 1;
  int s1 = static_cast<int>(ceil(f1));
  s1 = s1 < s2 ? s1 : s2;
  if (s1 - f1 > 1e-3) tap(s1 - 1, static_cast<float>((s1 - f1) / cell));
  for (int s = s1; s < s2; ++s) tap(s, static_cast<float>(1.0 / cell));
  if (f2 - s2 > 1e-3) {
    const double part = f2 - s2 < 1.0 ? f2 - s2 : 1.0;
    tap(s2, static_cast<float>((part < cell ? part : cell) / cell));
  }
}
}  // namespace detail

// Whether cv::resize takes its fast area path (an integer factor in both directions): a box mean.
FOVEAL_HD inline bool area_is_box(int sw, int sh, int dw, int dh) { return sw % dw == 0 && sh % dh == 0; }

FOVEAL_HD inline float resize_area_at(const float* s, int sw, int sh, int cn, int dw, int dh, int x, int y, int c) {
  if (area_is_box(sw, sh, dw, dh)) {
    const int fx = sw / dw, fy = sh / dh;
    float sum = 0.0f;
    for (int j = 0; j < fy; ++j) {
      const float* row = s + static_cast<size_t>(y * fy + j) * sw * cn;
      for (int i = 0; i < fx; ++i) sum += row[(x * fx + i) * cn + c];
    }
    return sum * static_cast<float>(1.0 / (fx * fy));
  }
  float sum = 0.0f;
  detail::area_taps(sh, dh, y, [&](int sy, float wy) {
    const float* row = s + static_cast<size_t>(sy) * sw * cn;
    float h = 0.0f;
    detail::area_taps(sw, dw, x, [&](int sx, float wx) { h += row[sx * cn + c] * wx; });
    sum += h * wy;
  });
  return sum;
}

// cv::resize with INTER_LINEAR: the source sampled at ((x + ½)·sw/dw − ½, …), clamped to the
// edge pixels (halving exactly, where OpenCV takes a 2 × 2 box mean, gives the same mean).
namespace detail {
FOVEAL_HD inline void linear_tap(int ssize, int dsize, int d, int& s0, int& s1, float& w1) {
  const double scale = 1.0 / (static_cast<double>(dsize) / ssize);
  float f = static_cast<float>((d + 0.5) * scale - 0.5);
  int s = static_cast<int>(floorf(f));
  f -= s;
  if (s < 0) f = 0.0f, s = 0;
  if (s >= ssize - 1) f = 0.0f, s = ssize - 1;
  s0 = s;
  s1 = s + 1 < ssize ? s + 1 : ssize - 1;
  w1 = f;
}
}  // namespace detail

FOVEAL_HD inline float resize_linear_at(const float* s, int sw, int sh, int cn, int dw, int dh, int x, int y, int c) {
  int x0, x1, y0, y1;
  float fx, fy;
  detail::linear_tap(sw, dw, x, x0, x1, fx);
  detail::linear_tap(sh, dh, y, y0, y1, fy);
  const float* r0 = s + static_cast<size_t>(y0) * sw * cn;
  const float* r1 = s + static_cast<size_t>(y1) * sw * cn;
  const float h0 = r0[x0 * cn + c] * (1.0f - fx) + r0[x1 * cn + c] * fx;
  const float h1 = r1[x0 * cn + c] * (1.0f - fx) + r1[x1 * cn + c] * fx;
  return h0 * (1.0f - fy) + h1 * fy;
}

// cv::remap with float maps, INTER_LINEAR and BORDER_REFLECT at (mx, my): the coordinates rounded
// to 1/32 of a pixel (INTER_TAB_SIZE), OpenCV's tabulated bilinear weights.
FOVEAL_HD inline float remap_linear_at(const float* s, int w, int h, int cn, float mx, float my, int c) {
#if defined(__CUDA_ARCH__)
  const int X = __float2int_rn(mx * 32.0f), Y = __float2int_rn(my * 32.0f);
#else
  const int X = static_cast<int>(std::lrint(mx * 32.0f)), Y = static_cast<int>(std::lrint(my * 32.0f));
#endif
  const int sx = X >> 5, sy = Y >> 5;
  const float tx = (X & 31) * (1.0f / 32.0f), ty = (Y & 31) * (1.0f / 32.0f);
  const float w00 = (1.0f - ty) * (1.0f - tx), w01 = (1.0f - ty) * tx, w10 = ty * (1.0f - tx), w11 = ty * tx;
  const int x0 = reflect(sx, w), x1 = reflect(sx + 1, w), y0 = reflect(sy, h), y1 = reflect(sy + 1, h);
  const float* r0 = s + static_cast<size_t>(y0) * w * cn;
  const float* r1 = s + static_cast<size_t>(y1) * w * cn;
  return r0[x0 * cn + c] * w00 + r0[x1 * cn + c] * w01 + r1[x0 * cn + c] * w10 + r1[x1 * cn + c] * w11;
}

}  // namespace foveal::resample
