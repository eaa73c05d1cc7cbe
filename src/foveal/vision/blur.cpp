// foveal/vision/blur.cpp — the gather blur, parallel over rows.
#include "foveal/vision/blur.h"

#include "foveal/util/error.h"

#include <tbb/parallel_for.h>

#include <algorithm>
#include <cmath>
#include <numbers>
#include <type_traits>

namespace foveal {

TapPattern make_tap_pattern(int taps) {
  if (taps < 1 || taps > 4096) fail("--blur-taps: must be in [1, 4096], got {}", taps);
  TapPattern t;
  t.offset.push_back({0, 0});
  const double golden = std::numbers::pi * (3.0 - std::sqrt(5.0));
  for (int k = 0; k < taps; ++k) {
    const double r = std::sqrt((k + 0.5) / taps), a = k * golden;
    t.offset.push_back(glm::vec2(r * std::cos(a), r * std::sin(a)));
  }
  // Each spiral point stands for an equal area of the disc; the centre for a tiny one
  for (size_t i = 0; i < t.offset.size(); ++i) {
    const float r2 = glm::dot(t.offset[i], t.offset[i]);
    t.weight.push_back(std::exp(-4.5f * r2) * (i == 0 ? 1.0f / taps : 1.0f));
  }
  return t;
}

int taps_for_diameter(float d, int max_taps) {
  if (!(d >= 0.25f)) return 0;
  // About one tap per pixel inside 2.1σ of the centre, where the Gaussian's weight lies (fewer
  // broke the 0.02 bound against OpenCV's Gaussian in the tests)
  const int area = static_cast<int>(std::ceil(0.4f * d * d));
  return std::clamp(area, std::min(8, max_taps), max_taps);
}

namespace {

// Texels of up to four channels, padded to four so that a bilinear read is four vector loads.
typedef float v4 __attribute__((vector_size(16)));

struct Level {
  int width = 0, height = 0;
  std::vector<v4> texels;
};

// The image (padded to four channels) and half-resolution copies (2×2 box), so that a large
// CoC's taps, spaced several texels apart, read pre-averaged pixels instead of aliasing.
std::vector<Level> pyramid(const Image& img, int levels) {
  std::vector<Level> out(1);
  out[0].width = img.width;
  out[0].height = img.height;
  out[0].texels.resize(size_t(img.width) * img.height);
  const int ch = img.channels;
  tbb::parallel_for(tbb::blocked_range<size_t>(0, out[0].texels.size(), 4096), [&](const tbb::blocked_range<size_t>& r) {
    for (size_t i = r.begin(); i < r.end(); ++i) {
      v4 t = {0, 0, 0, 0};
      for (int c = 0; c < ch; ++c) t[c] = img.pixels[i * ch + c];
      out[0].texels[i] = t;
    }
  });
  for (int l = 1; l < levels; ++l) {
    const Level& src = out.back();
    if (src.width < 4 || src.height < 4) break;
    Level dst;
    dst.width = (src.width + 1) / 2;
    dst.height = (src.height + 1) / 2;
    dst.texels.resize(size_t(dst.width) * dst.height);
    tbb::parallel_for(tbb::blocked_range<int>(0, dst.height, 16), [&](const tbb::blocked_range<int>& rows) {
      for (int y = rows.begin(); y < rows.end(); ++y)
        for (int x = 0; x < dst.width; ++x) {
          const int x0 = 2 * x, y0 = 2 * y, x1 = std::min(x0 + 1, src.width - 1), y1 = std::min(y0 + 1, src.height - 1);
          const v4* row0 = &src.texels[size_t(y0) * src.width];
          const v4* row1 = &src.texels[size_t(y1) * src.width];
          dst.texels[size_t(y) * dst.width + x] = 0.25f * (row0[x0] + row0[x1] + row1[x0] + row1[x1]);
        }
    });
    out.push_back(std::move(dst));
  }
  return out;
}

// Inlined into the per-CPU builds of gather_rows (a call would run the baseline build)
#define FOVEAL_INLINE __attribute__((always_inline))

// Taps spaced wider than this many texels read the next coarser level
constexpr float kLevelSpacing = 2.0f;
// Tiles of the smallest CoC, to skip the scatter-aware test where every tap passes it
constexpr int kTile = 16;

// What every pixel's gather reads.
struct GatherContext {
  const Image& img;
  const std::vector<float>& coc;  // per pixel, at most max_diameter_px (NaN and infinity: that)
  const BlurParams& params;
  const CocShape* shape;
  const std::vector<Level>& levels;
  const std::vector<std::vector<float>>& min_quad;  // per level: smallest CoC under each texel's 2×2 bilinear footprint
  glm::vec2 along, across;             // the ellipse's axes in image coordinates
  const std::vector<TapPattern>& patterns;  // patterns[n − first_count]: the pattern of n taps
  int first_count;
  const std::vector<float>& tile_min;  // smallest CoC of each kTile × kTile tile
  int tiles_x, tiles_y;
  Image& out;

  // The smallest CoC of the tiles within r pixels of (x, y)
  float min_coc_around(int x, int y, float r) const {
    const int tx0 = std::max(0, int(x - r) / kTile), tx1 = std::min(tiles_x - 1, int(x + r) / kTile);
    const int ty0 = std::max(0, int(y - r) / kTile), ty1 = std::min(tiles_y - 1, int(y + r) / kTile);
    float m = INFINITY;
    for (int ty = ty0; ty <= ty1; ++ty)
      for (int tx = tx0; tx <= tx1; ++tx) m = std::min(m, tile_min[size_t(ty) * tiles_x + tx]);
    return m;
  }

  const TapPattern& pattern_for(int taps) const {
    return patterns[size_t(std::clamp(taps - first_count, 0, int(patterns.size()) - 1))];
  }
};

// One pixel of the gather: taps over its own CoC (diameter d, clamped), Gaussian-weighted,
// bilinear reads; with `check`, a tap counts only where its own CoC reaches the pixel.
template <int CH>
inline FOVEAL_INLINE void gather_pixel(const GatherContext& g, int x, int y, float d) {
  const int w = g.img.width;
  const size_t i = size_t(y) * w + x;
  const int n = taps_for_diameter(d, g.params.taps);
  float* dst = &g.out.pixels[i * CH];
  if (n == 0) {  // sharp: the pixel as it is
    for (int c = 0; c < CH; ++c) dst[c] = g.img.pixels[i * CH + c];
    return;
  }
  const TapPattern& taps = g.pattern_for(n);
  // Taps are about `spacing` pixels apart (within 2σ); read the level whose pixels are that large
  const float spacing = d / 3.0f * std::sqrt(3.14159f / float(taps.offset.size()));
  int level = 0;
  while (level + 1 < int(g.levels.size()) && spacing >= kLevelSpacing * float(1 << level)) ++level;
  const Level& src = g.levels[level];
  // A level-L texel is a 2^L box average, which has already blurred by a variance of
  // (4^L − 1)/12 px² per axis: the taps add only what is missing to σ² = (d/6)²
  const float sigma2 = d * d / 36.0f, prefilter = (float(1 << (2 * level)) - 1.0f) / 12.0f;
  const float reach_px = 3.0f * std::sqrt(std::max(sigma2 - prefilter, 0.25f * sigma2));  // the taps' disc radius, pixels
  const float scale = 1.0f / float(1 << level), radius = reach_px * scale;
  // The scatter-aware test can fail only where some pixel under a tap's footprint (within the
  // taps' reach plus a texel pair) has a CoC below d − 1: taps lie within d/2 of the pixel, and a
  // footprint whose smallest CoC is r passes when r/2 + 1/2 reaches the tap
  const bool check = g.params.scatter_aware && g.min_coc_around(x, y, reach_px + 2.0f * float(1 << level)) < d - 1.0f;
  const float cx = (x + 0.5f) * scale - 0.5f, cy = (y + 0.5f) * scale - 0.5f;
  const int sw = src.width, sh = src.height;
  v4 sum = {0, 0, 0, 0};
  float total = 0;
  // Every tap's 2×2 footprint inside the image: no clamping needed
  const bool interior = cx - radius >= 0 && cy - radius >= 0 && cx + radius < float(sw - 2) && cy + radius < float(sh - 2);
  const v4* texels = src.texels.data();
  const float* quad = g.min_quad[level].data();
  const float texel_px = float(1 << level);
  const glm::vec2 sc = g.shape ? g.shape->scale[i] : glm::vec2(1.0f);
  // The taps, with what is known per pixel (scatter-aware test, clamping at the border, an
  // elliptical CoC) decided outside the loop so that the common case runs without branches
  auto taps_loop = [&](auto checked, auto clamped, auto elliptical) FOVEAL_INLINE {
    for (size_t k = 0; k < taps.offset.size(); ++k) {
      glm::vec2 o = taps.offset[k];
      if constexpr (decltype(elliptical)::value) o = o.x * sc.x * g.along + o.y * sc.y * g.across;  // stretched into the ellipse
      float sx = cx + radius * o.x, sy = cy + radius * o.y;
      int dx1 = 1, dy1 = sw;
      if constexpr (decltype(clamped)::value) {
        sx = std::clamp(sx, 0.0f, float(sw - 1));
        sy = std::clamp(sy, 0.0f, float(sh - 1));
        if (sw < 2) dx1 = 0;
        if (sh < 2) dy1 = 0;
      }
      int x0 = int(sx), y0 = int(sy);
      if constexpr (decltype(clamped)::value) {
        x0 = std::min(x0, std::max(sw - 2, 0));
        y0 = std::min(y0, std::max(sh - 2, 0));
      }
      float wk = taps.weight[k];
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
      const v4* p = texels + size_t(y0) * sw + x0;
      const v4 top = p[0] + fx * (p[dx1] - p[0]), bottom = p[dy1] + fx * (p[dy1 + dx1] - p[dy1]);
      sum += wk * (top + fy * (bottom - top));
      total += wk;
    }
  };
  // Each combination of the three is its own instantiation of the loop
  auto when = [](bool b, auto next) FOVEAL_INLINE {
    if (b) next(std::true_type{});
    else next(std::false_type{});
  };
  when(check, [&](auto checked) FOVEAL_INLINE {
    when(!interior, [&](auto clamped) FOVEAL_INLINE {
      when(g.shape != nullptr, [&](auto elliptical) FOVEAL_INLINE { taps_loop(checked, clamped, elliptical); });
    });
  });
  if (!(total > 0)) {  // nothing reached (cannot happen with the centre tap, kept for safety)
    for (int c = 0; c < CH; ++c) dst[c] = g.img.pixels[i * CH + c];
    return;
  }
  for (int c = 0; c < CH; ++c) dst[c] = sum[c] / total;
}

// Rows [y0, y1) of the output. Built twice where the compiler can: for x86-64-v3 (AVX2 and fused
// multiply-adds; 20–25 % faster, measured with bench/foveal_microbench) and for the baseline,
// chosen at load time by the CPU. The two round differently in the last bits, so a CPU without
// AVX2 may give an image a few 1e-7 apart; on one machine the image never depends on threads.
template <int CH>
inline FOVEAL_INLINE void gather_rows_of(const GatherContext& g, int y0, int y1) {
  const int w = g.img.width;
  for (int y = y0; y < y1; ++y)
    for (int x = 0; x < w; ++x) gather_pixel<CH>(g, x, y, g.coc[size_t(y) * w + x]);
}

#if defined(__GNUC__) && !defined(__clang__) && defined(__x86_64__) && !defined(__SANITIZE_ADDRESS__)
__attribute__((target_clones("arch=x86-64-v3", "default")))
#endif
void gather_rows(const GatherContext& g, int y0, int y1) {
  switch (g.img.channels) {
    case 1: gather_rows_of<1>(g, y0, y1); break;
    case 2: gather_rows_of<2>(g, y0, y1); break;
    case 3: gather_rows_of<3>(g, y0, y1); break;
    default: gather_rows_of<4>(g, y0, y1); break;
  }
}

}  // namespace

Image variable_blur(const Image& img, const std::vector<float>& coc, const BlurParams& params, const CocShape* shape) {
  if (coc.size() != size_t(img.width) * img.height) fail("blur: {} CoC values for a {}x{} image", coc.size(), img.width, img.height);
  if (shape && shape->scale.size() != coc.size()) fail("blur: {} CoC shapes for {} pixels", shape->scale.size(), coc.size());
  // The ellipse's axes in image coordinates (y down)
  const float axis_rad = shape ? glm::radians(shape->axis_deg) : 0.0f;
  const glm::vec2 along(std::cos(axis_rad), -std::sin(axis_rad)), across(std::sin(axis_rad), std::cos(axis_rad));
  // A pattern for every tap count in use (8 … taps)
  const int first_count = std::min(8, params.taps);
  std::vector<TapPattern> patterns;
  for (int n = first_count; n <= params.taps; ++n) patterns.push_back(make_tap_pattern(n));
  const int w = img.width, h = img.height, ch = img.channels;
  if (ch < 1 || ch > 4) fail("blur: images of 1 to 4 channels, got {}", ch);
  const std::vector<Level> levels = pyramid(img, 5);
  // The CoCs clamped once (NaN and infinity: the largest), then the smallest of each tile
  std::vector<float> clamped(coc.size());
  tbb::parallel_for(tbb::blocked_range<size_t>(0, coc.size(), 4096), [&](const tbb::blocked_range<size_t>& r) {
    for (size_t i = r.begin(); i < r.end(); ++i)
      clamped[i] = std::isfinite(coc[i]) ? std::min(coc[i], params.max_diameter_px) : params.max_diameter_px;
  });
  const int tiles_x = (w + kTile - 1) / kTile, tiles_y = (h + kTile - 1) / kTile;
  std::vector<float> tile_min(size_t(tiles_x) * tiles_y, INFINITY);
  for (int y = 0; y < h; ++y)
    for (int x = 0; x < w; ++x) {
      float& m = tile_min[size_t(y / kTile) * tiles_x + x / kTile];
      m = std::min(m, clamped[size_t(y) * w + x]);
    }
  // Smallest CoC under each texel of each level (a min pyramid), then under each texel's 2×2
  // bilinear footprint (x, x+1) × (y, y+1)
  std::vector<std::vector<float>> min_quad(levels.size());
  std::vector<float> below = clamped, above;
  for (size_t l = 0; l < levels.size(); ++l) {
    const int lw = levels[l].width, lh = levels[l].height;
    if (l > 0) {  // min over the 2×2 texels of the level below
      const int bw = levels[l - 1].width, bh = levels[l - 1].height;
      above.resize(size_t(lw) * lh);
      for (int y = 0; y < lh; ++y)
        for (int x = 0; x < lw; ++x) {
          const int x0 = 2 * x, y0 = 2 * y, x1 = std::min(x0 + 1, bw - 1), y1 = std::min(y0 + 1, bh - 1);
          above[size_t(y) * lw + x] = std::min(std::min(below[size_t(y0) * bw + x0], below[size_t(y0) * bw + x1]),
                                               std::min(below[size_t(y1) * bw + x0], below[size_t(y1) * bw + x1]));
        }
      std::swap(below, above);
    }
    std::vector<float>& quad = min_quad[l];
    quad.resize(size_t(lw) * lh);
    tbb::parallel_for(tbb::blocked_range<int>(0, lh, 16), [&](const tbb::blocked_range<int>& rows) {
      for (int y = rows.begin(); y < rows.end(); ++y)
        for (int x = 0; x < lw; ++x) {
          const int x1 = std::min(x + 1, lw - 1), y1 = std::min(y + 1, lh - 1);
          quad[size_t(y) * lw + x] = std::min(std::min(below[size_t(y) * lw + x], below[size_t(y) * lw + x1]),
                                              std::min(below[size_t(y1) * lw + x], below[size_t(y1) * lw + x1]));
        }
    });
  }
  Image out(w, h, ch);
  const GatherContext context{img, clamped, params, shape, levels, min_quad, along, across, patterns, first_count, tile_min, tiles_x, tiles_y, out};
  tbb::parallel_for(tbb::blocked_range<int>(0, h, 4), [&](const tbb::blocked_range<int>& rows) {
    gather_rows(context, rows.begin(), rows.end());
  });
  return out;
}

}  // namespace foveal
