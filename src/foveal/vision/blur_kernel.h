// foveal/vision/blur_kernel.h — one pixel of the variable blur, written once for the CPU
// (blur.cpp, oneTBB rows) and the GPU (a kernel over pixels).
//
// The gather reads a pyramid of the image (texels of four channels; the CPU's are GCC vectors,
// the GPU's glm::vec4) through plain pointers in host or device memory. What the pixel needs is
// described in blur.h; the preparation (clamped CoCs, the pyramid, the smallest CoC under each
// texel's bilinear footprint and of each 16 × 16 tile) is done by each backend before the gather.
#pragma once

#include "foveal/util/hd.h"

#include <glm/glm.hpp>

#include <algorithm>
#include <cmath>
#include <cstddef>
#include <limits>
#include <type_traits>

// Always inlined: FOVEAL_FORCE_INLINE on functions, FOVEAL_INLINE on lambdas (the CPU's per-CPU
// builds of the gather would otherwise call the baseline build; the GPU inlines by itself)
#if defined(__CUDACC__)
#define FOVEAL_FORCE_INLINE __forceinline__
#define FOVEAL_INLINE
#else
#define FOVEAL_FORCE_INLINE inline __attribute__((always_inline))
#define FOVEAL_INLINE __attribute__((always_inline))
#endif

namespace foveal {

// Taps for a CoC diameter d (pixels): about one per pixel within 2.1σ (0.4·d²), at least 8, at
// most `max_taps`; 0 below a quarter pixel (the pixel is copied). About one tap per pixel inside
// 2.1σ of the centre, where the Gaussian's weight lies (fewer broke the 0.02 bound against
// OpenCV's Gaussian in the tests).
FOVEAL_HD inline int taps_for_diameter(float d, int max_taps) {
  if (!(d >= 0.25f)) return 0;
  const int area = static_cast<int>(std::ceil(0.4f * d * d));
  const int least = 8 < max_taps ? 8 : max_taps;
  return area < least ? least : (area > max_taps ? max_taps : area);
}

namespace blur {

constexpr int kMaxLevels = 5;          // the image and four 2×2-averaged copies
constexpr float kLevelSpacing = 2.0f;  // taps spaced wider than this many texels read the next coarser level
constexpr int kTile = 16;              // tiles of the smallest CoC, to skip the scatter-aware test where all taps pass

template <class Texel>
struct LevelView {
  int width = 0, height = 0;
  const Texel* texels = nullptr;
  const float* min_quad = nullptr;  // smallest CoC under each texel's 2×2 bilinear footprint
};

// Everything one pixel's gather reads.
template <class Texel>
struct GatherView {
  int width = 0, height = 0;
  const float* coc = nullptr;           // per pixel, clamped to [0, max diameter] (NaN, ∞ → the max)
  const glm::vec2* shape = nullptr;     // per pixel (along, across) ≤ 1, or null for round CoCs
  glm::vec2 along{1, 0}, across{0, 1};  // the ellipse's axes in image coordinates
  LevelView<Texel> levels[kMaxLevels];
  int level_count = 0;
  // The tap patterns of first_count … max_taps taps, end to end: pattern n (n + 1 points, the
  // centre first) starts at pattern_start[n − first_count]
  const glm::vec2* offsets = nullptr;
  const float* weights = nullptr;
  const int* pattern_start = nullptr;
  int first_count = 0, max_taps = 0;
  bool scatter_aware = true;
  const float* tile_min = nullptr;  // smallest CoC of each kTile × kTile tile
  int tiles_x = 0, tiles_y = 0;

  // The smallest CoC of the tiles within r pixels of (x, y)
  FOVEAL_HD float min_coc_around(int x, int y, float r) const {
    const int tx0 = std::max(0, int(x - r) / kTile), tx1 = std::min(tiles_x - 1, int(x + r) / kTile);
    const int ty0 = std::max(0, int(y - r) / kTile), ty1 = std::min(tiles_y - 1, int(y + r) / kTile);
    float m = INFINITY;
    for (int ty = ty0; ty <= ty1; ++ty)
      for (int tx = tx0; tx <= tx1; ++tx) m = std::min(m, tile_min[size_t(ty) * tiles_x + tx]);
    return m;
  }
};

template <class Texel>
FOVEAL_HD inline Texel zero_texel() {
  Texel t{};
  for (int c = 0; c < 4; ++c) t[c] = 0.0f;
  return t;
}

// Pixel (x, y) of the output (`dst`, CH channels) from `image` (CH channels per pixel): taps over
// its own CoC d (clamped), Gaussian-weighted, bilinear reads of the level whose texels match the
// taps' spacing; scatter-aware where the tiles say a smaller CoC is near.
template <int CH, class Texel>
FOVEAL_HD FOVEAL_FORCE_INLINE void gather_pixel(const GatherView<Texel>& g, const float* image, float* dst, int x, int y) {
  const size_t i = size_t(y) * g.width + x;
  const float d = g.coc[i];
  const int n = taps_for_diameter(d, g.max_taps);
  if (n == 0) {  // sharp: the pixel as it is
    for (int c = 0; c < CH; ++c) dst[c] = image[i * CH + c];
    return;
  }
  const int pattern = std::min(std::max(n - g.first_count, 0), g.max_taps - g.first_count);
  const int tap_count = pattern + g.first_count + 1;
  const glm::vec2* offsets = g.offsets + g.pattern_start[pattern];
  const float* weights = g.weights + g.pattern_start[pattern];
  // Taps are about `spacing` pixels apart (within 2σ); read the level whose pixels are that large
  const float spacing = d / 3.0f * std::sqrt(3.14159f / float(tap_count));
  int level = 0;
  while (level + 1 < g.level_count && spacing >= kLevelSpacing * float(1 << level)) ++level;
  const LevelView<Texel>& src = g.levels[level];
  // A level-L texel is a 2^L box average, which has already blurred by a variance of
  // (4^L − 1)/12 px² per axis: the taps add only what is missing to σ² = (d/6)²
  const float sigma2 = d * d / 36.0f, prefilter = (float(1 << (2 * level)) - 1.0f) / 12.0f;
  const float reach_px = 3.0f * std::sqrt(std::max(sigma2 - prefilter, 0.25f * sigma2));  // the taps' disc radius, pixels
  const float scale = 1.0f / float(1 << level), radius = reach_px * scale;
  // The scatter-aware test can fail only where some pixel under a tap's footprint (within the
  // taps' reach plus a texel pair) has a CoC below d − 1: taps lie within d/2 of the pixel, and a
  // footprint whose smallest CoC is r passes when r/2 + 1/2 reaches the tap
  const bool check = g.scatter_aware && g.min_coc_around(x, y, reach_px + 2.0f * float(1 << level)) < d - 1.0f;
  const float cx = (x + 0.5f) * scale - 0.5f, cy = (y + 0.5f) * scale - 0.5f;
  const int sw = src.width, sh = src.height;
  Texel sum = zero_texel<Texel>();
  float total = 0;
  // Every tap's 2×2 footprint inside the image: no clamping needed
  const bool interior = cx - radius >= 0 && cy - radius >= 0 && cx + radius < float(sw - 2) && cy + radius < float(sh - 2);
  const Texel* texels = src.texels;
  const float* quad = src.min_quad;
  const float texel_px = float(1 << level);
  const glm::vec2 sc = g.shape ? g.shape[i] : glm::vec2(1.0f);
  // The taps, with what is known per pixel (scatter-aware test, clamping at the border, an
  // elliptical CoC) decided outside the loop so that the common case runs without branches
  auto taps_loop = [&](auto checked, auto clamped, auto elliptical) FOVEAL_INLINE {
    for (int k = 0; k < tap_count; ++k) {
      glm::vec2 o = offsets[k];
      if constexpr (decltype(elliptical)::value) o = o.x * sc.x * g.along + o.y * sc.y * g.across;  // stretched into the ellipse
      float sx = cx + radius * o.x, sy = cy + radius * o.y;
      int dx1 = 1, dy1 = sw;
      if constexpr (decltype(clamped)::value) {
        sx = std::min(std::max(sx, 0.0f), float(sw - 1));
        sy = std::min(std::max(sy, 0.0f), float(sh - 1));
        if (sw < 2) dx1 = 0;
        if (sh < 2) dy1 = 0;
      }
      int x0 = int(sx), y0 = int(sy);
      if constexpr (decltype(clamped)::value) {
        x0 = std::min(x0, std::max(sw - 2, 0));
        y0 = std::min(y0, std::max(sh - 2, 0));
      }
      float wk = weights[k];
      if constexpr (decltype(checked)::value) {
        // A tap counts only if the CoC of every pixel under its bilinear footprint reaches this
        // pixel (scatter-aware: a sharp point does not spread, and no sharp texel leaks in
        // bilinearly or through a coarse level's averages). One read: the footprint's smallest CoC.
        const float ex = (sx + 0.5f) * texel_px - 0.5f - float(x), ey = (sy + 0.5f) * texel_px - 0.5f - float(y);
        const float reach = 0.5f * quad[size_t(y0) * sw + x0] + 0.5f * texel_px;
        wk = reach * reach >= ex * ex + ey * ey ? wk : 0.0f;
      }
      // Bilinear read as two horizontal lerps and a vertical one
      const float fx = sx - float(x0), fy = sy - float(y0);
      const Texel* p = texels + size_t(y0) * sw + x0;
      const Texel top = p[0] + fx * (p[dx1] - p[0]), bottom = p[dy1] + fx * (p[dy1 + dx1] - p[dy1]);
      sum += wk * (top + fy * (bottom - top));
      total += wk;
    }
  };
  // Each combination of the three is its own instantiation of the loop
  auto when = [](bool b, auto next) FOVEAL_INLINE {
    if (b)
      next(std::true_type{});
    else
      next(std::false_type{});
  };
  when(check, [&](auto checked) FOVEAL_INLINE {
    when(!interior, [&](auto clamped) FOVEAL_INLINE {
      when(g.shape != nullptr, [&](auto elliptical) FOVEAL_INLINE { taps_loop(checked, clamped, elliptical); });
    });
  });
  if (!(total > 0)) {  // nothing reached (cannot happen with the centre tap, kept for safety)
    for (int c = 0; c < CH; ++c) dst[c] = image[i * CH + c];
    return;
  }
  for (int c = 0; c < CH; ++c) dst[c] = sum[c] / total;
}

// The size of the level above one of w × h texels (half, rounded up); false when w × h is too
// small to halve (under 4 texels a side): the pyramid ends there.
inline bool next_level(int* w, int* h) {
  if (*w < 4 || *h < 4) return false;
  *w = (*w + 1) / 2;
  *h = (*h + 1) / 2;
  return true;
}

// The preparation, per element, for both backends.
// A texel of level l + 1: the mean of the 2×2 texels below (clamped at the odd edge).
template <class Texel>
FOVEAL_HD inline Texel box_average(const Texel* below, int bw, int bh, int x, int y) {
  const int x0 = 2 * x, y0 = 2 * y, x1 = std::min(x0 + 1, bw - 1), y1 = std::min(y0 + 1, bh - 1);
  const Texel* row0 = below + size_t(y0) * bw;
  const Texel* row1 = below + size_t(y1) * bw;
  return 0.25f * (row0[x0] + row0[x1] + row1[x0] + row1[x1]);
}
// The smallest of a 2×2 block whose corner is (x0, y0) (x1, y1: the other corner, clamped).
FOVEAL_HD inline float min_of_block(const float* v, int w, int x0, int y0, int x1, int y1) {
  return std::min(std::min(v[size_t(y0) * w + x0], v[size_t(y0) * w + x1]), std::min(v[size_t(y1) * w + x0], v[size_t(y1) * w + x1]));
}
// The smallest (clamped) CoC of tile (tx, ty): its kTile × kTile pixels, cut at the image's edge.
FOVEAL_HD inline float tile_minimum(const float* coc, int w, int h, int tx, int ty) {
  float m = std::numeric_limits<float>::infinity();
  const int x1 = std::min(w, (tx + 1) * kTile), y1 = std::min(h, (ty + 1) * kTile);
  for (int y = ty * kTile; y < y1; ++y)
    for (int x = tx * kTile; x < x1; ++x) m = std::min(m, coc[size_t(y) * w + x]);
  return m;
}
// A CoC as the gather reads it: at most `max_diameter`, NaN and infinity → the max.
FOVEAL_HD inline float clamp_coc(float coc, float max_diameter) { return std::isfinite(coc) ? std::min(coc, max_diameter) : max_diameter; }

}  // namespace blur
}  // namespace foveal
