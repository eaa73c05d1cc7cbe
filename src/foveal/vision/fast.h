// foveal/vision/fast.h — FAST-9 corners, per pixel, written once for the GPU and its test.
//
// The CPU finds corners with OpenCV (cv::FAST, TYPE_9_16, features.cpp). The GPU cannot call
// OpenCV, so its kernels call these functions, which give the same keypoints by construction,
// and the tests hold them to OpenCV's on the CPU (vision_test.cpp: every keypoint and score
// identical on rendered and natural images).
//
// The detector on the 16 pixels of a radius-3 Bresenham circle around a pixel of grey v, with
// d_k = v − p_k: the pixel is a corner at threshold t when 9 contiguous circle pixels are all
// darker than v − t or all brighter than v + t. With A = the largest, over the 16 runs of 9
// contiguous pixels, of the run's smallest d, and B the same for −d, that is max(A, B) > t; the
// response max(A, B) − 1 is the largest threshold at which it still is one (OpenCV's score).
// Non-maximum suppression keeps a corner whose score exceeds all 8 neighbours' (0 where no
// corner). Corners are looked for 3 pixels from the border, as OpenCV does.
#pragma once

#include "foveal/util/hd.h"

#include <cmath>
#include <cstdint>

namespace foveal::fast {

// The circle, clockwise from the pixel below (OpenCV's order; any rotation gives the same runs).
FOVEAL_HD inline void circle_offset(int k, int* dx, int* dy) {
  constexpr int8_t x[16] = {0, 1, 2, 3, 3, 3, 2, 1, 0, -1, -2, -3, -3, -3, -2, -1};
  constexpr int8_t y[16] = {3, 3, 2, 1, 0, -1, -2, -3, -3, -3, -2, -1, 0, 1, 2, 3};
  *dx = x[k & 15];
  *dy = y[k & 15];
}

// max(A, B) of the pixel (x, y), which lies at least 3 pixels inside the image.
FOVEAL_HD inline int response(const uint8_t* grey, int stride, int x, int y) {
  const uint8_t* p = grey + static_cast<long>(y) * stride + x;
  const int v = p[0];
  int d[16];
  for (int k = 0; k < 16; ++k) {
    int dx, dy;
    circle_offset(k, &dx, &dy);
    d[k] = v - p[dy * stride + dx];
  }
  int best = -256;
  for (int start = 0; start < 16; ++start) {
    int lo = 256, hi = -256;  // smallest and largest d of the run
    for (int j = 0; j < 9; ++j) {
      const int e = d[(start + j) & 15];
      lo = e < lo ? e : lo;
      hi = e > hi ? e : hi;
    }
    best = lo > best ? lo : best;    // a run all darker than v − lo
    best = -hi > best ? -hi : best;  // a run all brighter than v + |hi|
  }
  return best;
}

// The corner score at threshold t (OpenCV's response; 0 = not a corner). Outside the band 3
// pixels from the border there are no corners.
FOVEAL_HD inline int score(const uint8_t* grey, int width, int height, int x, int y, int threshold) {
  if (x < 3 || y < 3 || x >= width - 3 || y >= height - 3) return 0;
  const int r = response(grey, width, x, y);
  return r > threshold ? r - 1 : 0;
}

// Whether the corner of score s at (x, y) survives non-maximum suppression among the scores
// (0 for no corner) of a width × height image.
FOVEAL_HD inline bool is_local_maximum(const uint8_t* scores, int width, int height, int x, int y) {
  const int s = scores[static_cast<long>(y) * width + x];
  if (s == 0) return false;
  for (int dy = -1; dy <= 1; ++dy)
    for (int dx = -1; dx <= 1; ++dx) {
      if (dx == 0 && dy == 0) continue;
      const int nx = x + dx, ny = y + dy;
      if (nx < 0 || ny < 0 || nx >= width || ny >= height) continue;
      if (scores[static_cast<long>(ny) * width + nx] >= s) return false;
    }
  return true;
}

// The entry of srgb8_table() (features.h) for a linear value: clamped to [0, 1]; NaN and ±∞ → 0.
FOVEAL_HD inline int srgb8_index(float v) {
  const float f = std::isfinite(v) ? v : 0.0f;
  const float c = f < 0.0f ? 0.0f : (f > 1.0f ? 1.0f : f);
  return static_cast<int>(c * 4096.0f + 0.5f);
}

// BT.601 luma (0.299, 0.587, 0.114) of an 8-bit sRGB triple in 15-bit fixed point, rounded, as
// cv::cvtColor(COLOR_RGB2GRAY) computes it for bytes (the test checks all 2^24 triples).
FOVEAL_HD inline uint8_t grey_of(int r, int g, int b) { return static_cast<uint8_t>((r * 9798 + g * 19235 + b * 3735 + (1 << 14)) >> 15); }

}  // namespace foveal::fast
